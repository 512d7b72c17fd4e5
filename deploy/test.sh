#!/usr/bin/env bash
# From a fresh Debian 12 machine: install what is missing, build, run every test.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
"$root/deploy/install.sh"
"$root/deploy/build.sh"
ctest --test-dir "${LOCALIZER_BUILD_DIR:-$root/build}" --output-on-failure -j "$(nproc 2>/dev/null || echo 2)"
