# Dashboard browser test: Debian's headless Chromium (/usr/bin/chromium),
# driven by playwright-core (tests/browser/node_modules, from `npm ci`),
# against a canopen-gateway the test starts on a free port with the source
# web/ as its web root. Screenshots go to ${CMAKE_BINARY_DIR}/artifacts.
# Exit 77 = skipped: only when Chromium is missing and CI is unset.
# DASHBOARD_TOKEN_TEST=1 adds the token (auth on) part; ctest always runs it.
add_test(NAME browser.dashboard
         COMMAND bash ${CMAKE_CURRENT_LIST_DIR}/run.sh $<TARGET_FILE:canopen-gateway> ${CMAKE_BINARY_DIR}/artifacts)
set_tests_properties(browser.dashboard PROPERTIES
  LABELS "system;browser"
  RESOURCE_LOCK host_processes
  COST 900
  TIMEOUT 300
  SKIP_RETURN_CODE 77
  ENVIRONMENT "DASHBOARD_TOKEN_TEST=1")
