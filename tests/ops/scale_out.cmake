# Session-affine scale-out behind nginx: tests/ops/scale_out_test.py starts three
# localizer-server instances and nginx (deploy/nginx/localizer.conf, rendered with this run's
# ports) on loopback and checks spreading, resume through nginx and the loss of one instance.
# Included from tests/ops/CMakeLists.txt. Run with Debian's interpreter (python3-grpcio,
# python3-protobuf, python3-numpy); the test skips, with the reason printed, when nginx
# (Debian: nginx-light) is not installed. ctest -L ops
if(NOT LOCALIZER_PY_GEN)
  message(STATUS "tests/ops: no Python stubs (grpc_python_plugin missing); scale_out test skipped")
  return()
endif()
if(NOT TARGET localizer-server)
  message(STATUS "tests/ops: no localizer-server target; scale_out test skipped")
  return()
endif()
find_program(LOCALIZER_SYSTEM_PYTHON NAMES python3 PATHS /usr/bin NO_DEFAULT_PATH)
if(NOT LOCALIZER_SYSTEM_PYTHON)
  message(STATUS "tests/ops: /usr/bin/python3 not found; scale_out test skipped")
  return()
endif()

set(scale_out_env
    LOCALIZER_SERVER=$<TARGET_FILE:localizer-server>
    LOCALIZER_PY_GEN=${LOCALIZER_PY_GEN}
    LOCALIZER_PY_CLIENT_DIR=${LOCALIZER_PY_CLIENT_DIR}
    PYTHONDONTWRITEBYTECODE=1)

add_test(NAME ops_scale_out_nginx
         COMMAND ${LOCALIZER_SYSTEM_PYTHON} -m unittest -v scale_out_test
         WORKING_DIRECTORY ${CMAKE_CURRENT_LIST_DIR})
set_tests_properties(ops_scale_out_nginx PROPERTIES
  ENVIRONMENT "${scale_out_env}"
  TIMEOUT 300
  LABELS "ops")
