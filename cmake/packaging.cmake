# What `cmake --install build [--prefix DIR]` puts under the prefix:
#   bin/localizer-server, bin/localizer-cli (offline commands) and bin/localizer-cli-full
#   (every command; localizer-cli execs it from its own directory: clients/cli/full_cli.h)
#   lib/liblocalizer_<stage>.a                     one static library per engine stage
#   include/localizer/engine/<stage>/*.h           the engine's headers, paths as the code uses them
#   lib/cmake/localizer/localizerConfig.cmake      find_package(localizer CONFIG), with the
#   (+ ConfigVersion, Targets)                     imported targets localizer::engine (everything)
#                                                  and localizer::<stage> (core, array, tdoa, ...)
# A consumer writes
#   find_package(localizer 0.3 CONFIG REQUIRED)
#   target_link_libraries(app PRIVATE localizer::engine)
# and `#include "engine/tdoa/gcc_phat.h"`. tests/packaging installs into a scratch prefix and
# builds such a consumer.
include(CMakePackageConfigHelpers)

set(LOCALIZER_CMAKE_INSTALL_DIR ${CMAKE_INSTALL_LIBDIR}/cmake/localizer)

install(TARGETS ${LOCALIZER_ENGINE_TARGETS}
        EXPORT localizerTargets
        ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR})
# Every engine header: a stage's public header may include any header of the stages below it.
install(DIRECTORY ${PROJECT_SOURCE_DIR}/engine/
        DESTINATION ${LOCALIZER_INSTALL_INCLUDEDIR}/engine
        FILES_MATCHING PATTERN "*.h")
install(EXPORT localizerTargets
        NAMESPACE localizer::
        DESTINATION ${LOCALIZER_CMAKE_INSTALL_DIR})

configure_package_config_file(${CMAKE_CURRENT_LIST_DIR}/localizerConfig.cmake.in
                              ${CMAKE_CURRENT_BINARY_DIR}/localizerConfig.cmake
                              INSTALL_DESTINATION ${LOCALIZER_CMAKE_INSTALL_DIR})
# 0.x: a minor release may change the API, so only the same major.minor is compatible.
write_basic_package_version_file(${CMAKE_CURRENT_BINARY_DIR}/localizerConfigVersion.cmake
                                 VERSION ${PROJECT_VERSION}
                                 COMPATIBILITY SameMinorVersion)
install(FILES ${CMAKE_CURRENT_BINARY_DIR}/localizerConfig.cmake
              ${CMAKE_CURRENT_BINARY_DIR}/localizerConfigVersion.cmake
        DESTINATION ${LOCALIZER_CMAKE_INSTALL_DIR})

# The binaries link shared libraries from outside the system paths (the CUDA runtime and
# cuFFT under /usr/local/cuda when built with CUDA); keep those directories in the installed
# RUNPATH, as the build tree's binaries have them, instead of relying on ld.so.conf.
foreach(binary localizer-server localizer-cli localizer-cli-full localizer-loadgen)
  if(TARGET ${binary})
    set_target_properties(${binary} PROPERTIES INSTALL_RPATH_USE_LINK_PATH TRUE)
    install(TARGETS ${binary} RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
  endif()
endforeach()
