#!/usr/bin/env bash
# Sanitizer builds and their tests (docs/DEVELOPMENT.md). Incremental and idempotent.
# Usage: deploy/sanitize.sh asan|tsan [extra ctest options]
#   asan  ASan + UBSan build in build-asan; every GoogleTest test (engine, gpu stub, server,
#         clients), i.e. all but the ops and Python tests
#   tsan  TSan build in build-tsan; the service tests (tests/server), with the suppressions
#         of tests/sanitizers/tsan.supp (uninstrumented gRPC internals only)
# Only the test programs are built (no benchmarks, and for tsan only tests/server's). The
# presets are in CMakePresets.json. Environment: LOCALIZER_JOBS (default: nproc),
# LOCALIZER_CMAKE_ARGS (extra configure options, e.g. "-G Ninja -DCMAKE_CXX_COMPILER_LAUNCHER=ccache").
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
kind="${1:-}"
case "$kind" in
  asan) target=test_programs ;;
  tsan) target=test_programs_server ;;
  *) echo "usage: deploy/sanitize.sh asan|tsan [extra ctest options]" >&2; exit 2 ;;
esac
shift
jobs="${LOCALIZER_JOBS:-$(nproc 2>/dev/null || echo 2)}"
cd "$root"
if [ ! -f "build-$kind/CMakeCache.txt" ]; then
  # shellcheck disable=SC2086  # LOCALIZER_CMAKE_ARGS is a list of options
  cmake --preset "$kind" ${LOCALIZER_CMAKE_ARGS:-}
fi
cmake --build --preset "$kind" --target "$target" -j "$jobs"
ctest --preset "$kind" -j "$jobs" "$@"
