#!/usr/bin/env bash
# Runs the dashboard browser test (dashboard.test.mjs):
#   run.sh GATEWAY_BINARY [ARTIFACT_DIR]
# Exit 77 (ctest: skipped) only when Chromium is missing outside CI; with CI
# set, missing tools fail the test, so CI can never pass by skipping it.
set -euo pipefail

here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
gateway="${1:?usage: run.sh GATEWAY_BINARY [ARTIFACT_DIR]}"
artifacts="${2:-$PWD/artifacts}"
export CHROMIUM="${CHROMIUM:-/usr/bin/chromium}"

if [ ! -x "$CHROMIUM" ]; then
  if [ -n "${CI:-}" ]; then
    echo "browser.dashboard: FAIL: $CHROMIUM not found (CI is set; ./deploy/install-deps.sh installs it)"
    exit 1
  fi
  echo "browser.dashboard: SKIP: $CHROMIUM not found (apt-get install chromium, or ./deploy/install-deps.sh)"
  exit 77
fi
if ! command -v node >/dev/null; then
  echo "browser.dashboard: FAIL: node not found (./deploy/install-deps.sh installs nodejs and npm)"
  exit 1
fi
if [ ! -d "$here/node_modules/playwright-core" ]; then
  echo "browser.dashboard: FAIL: $here/node_modules is missing (./deploy/install-deps.sh runs npm ci there)"
  exit 1
fi

exec node "$here/dashboard.test.mjs" --gateway "$gateway" --web-root "$here/../../web" --artifacts "$artifacts"
