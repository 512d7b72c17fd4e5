# The live web view (label `ops`; included by CMakeLists.txt here): live_view_test.py starts
# localizer-server, streams a simulated session into it with localizer-cli, reads GET
# /sessions and has Debian's headless Chromium draw GET / (the Chromium part skips, with the
# reason printed, where no chromium is installed: Debian package `chromium`).
add_test(NAME ops_live_view
         COMMAND ${LOCALIZER_OPS_PYTHON} -m unittest -v live_view_test
         WORKING_DIRECTORY ${CMAKE_CURRENT_LIST_DIR})
set_tests_properties(ops_live_view PROPERTIES
  ENVIRONMENT "LOCALIZER_SERVER=$<TARGET_FILE:localizer-server>;LOCALIZER_CLI=$<TARGET_FILE:localizer-cli>;LOCALIZER_PY_GEN=${LOCALIZER_PY_GEN};LOCALIZER_PY_CLIENT_DIR=${LOCALIZER_PY_CLIENT_DIR};PYTHONDONTWRITEBYTECODE=1"
  TIMEOUT 240
  LABELS "ops")
