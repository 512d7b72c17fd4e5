# cmake -P script behind the ctest test `packaging_consumer` (tests/packaging/CMakeLists.txt):
#   1. cmake --install BUILD_DIR --prefix WORK_DIR/prefix   (what the build made; build first)
#   2. configure and build tests/packaging/consumer against that prefix alone
#   3. run the consumer (it exits non-zero unless the physics checks pass), the installed
#      localizer-cli --version (its RUNPATH finds the libraries it links), and
#      localizer-cli locate --help, which localizer-cli hands to the installed
#      localizer-cli-full beside it (clients/cli/full_cli.h)
# Any failing step fails the test with its output. Inputs (-D): BUILD_DIR, CONSUMER_DIR,
# WORK_DIR, GENERATOR, CXX_COMPILER.
foreach(var BUILD_DIR CONSUMER_DIR WORK_DIR GENERATOR CXX_COMPILER)
  if(NOT DEFINED ${var})
    message(FATAL_ERROR "install_and_consume.cmake: -D${var}=... missing")
  endif()
endforeach()

function(step name)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  message("== ${name}\n${out}${err}")
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "${name} failed (${rc})")
  endif()
endfunction()

file(REMOVE_RECURSE ${WORK_DIR})
set(prefix ${WORK_DIR}/prefix)
step("install" ${CMAKE_COMMAND} --install ${BUILD_DIR} --prefix ${prefix})
# The consumer sees the scratch prefix only: CMAKE_FIND_USE_PACKAGE_REGISTRY off, and no
# localizer elsewhere on CMAKE_PREFIX_PATH. Eigen3 and FFTW3 come from the system.
step("configure consumer" ${CMAKE_COMMAND} -S ${CONSUMER_DIR} -B ${WORK_DIR}/consumer -G ${GENERATOR}
     -DCMAKE_BUILD_TYPE=Release -DCMAKE_CXX_COMPILER=${CXX_COMPILER} -DCMAKE_PREFIX_PATH=${prefix}
     -DCMAKE_FIND_USE_PACKAGE_REGISTRY=OFF)
file(STRINGS ${WORK_DIR}/consumer/CMakeCache.txt found REGEX "^localizer_DIR:")
if(NOT found MATCHES "=${prefix}/")
  message(FATAL_ERROR "the consumer found localizer elsewhere than the scratch prefix: ${found}")
endif()
step("build consumer" ${CMAKE_COMMAND} --build ${WORK_DIR}/consumer)
step("run consumer" ${WORK_DIR}/consumer/consumer)
step("installed localizer-cli" ${prefix}/bin/localizer-cli --version)
execute_process(COMMAND ${prefix}/bin/localizer-cli locate --help RESULT_VARIABLE rc OUTPUT_VARIABLE out
                ERROR_VARIABLE err)
message("== installed localizer-cli locate --help (through localizer-cli-full)\n${out}${err}")
if(NOT rc EQUAL 0 OR NOT out MATCHES "usage: localizer-cli locate --server")
  message(FATAL_ERROR "installed localizer-cli locate --help did not reach localizer-cli-full (${rc})")
endif()
file(REMOVE_RECURSE ${WORK_DIR})
