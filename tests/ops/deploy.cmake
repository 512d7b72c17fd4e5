# The deploy files against real components (label `ops`; included by CMakeLists.txt here):
#   ops_prometheus   promtool checks and rule unit tests, and a real Prometheus scraping two
#                    live instances with the shipped config
#   ops_dashboard    every metric the Grafana dashboard and the alert rules read is exposed
#   ops_deploy_files container files and Kubernetes manifests, parsed and cross-checked
foreach(name prometheus dashboard deploy_files)
  add_test(NAME ops_${name}
           COMMAND ${LOCALIZER_OPS_PYTHON} -m unittest -v ${name}_test
           WORKING_DIRECTORY ${CMAKE_CURRENT_SOURCE_DIR})
  set_tests_properties(ops_${name} PROPERTIES
    ENVIRONMENT "LOCALIZER_SERVER=$<TARGET_FILE:localizer-server>;LOCALIZER_CLI=$<TARGET_FILE:localizer-cli>;PYTHONDONTWRITEBYTECODE=1"
    TIMEOUT 240
    LABELS "ops")
endforeach()
