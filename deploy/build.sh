#!/usr/bin/env bash
# Configures and builds localizer in ./build (Release, -O3). Incremental and idempotent.
# Usage: deploy/build.sh [--target NAME ...] [extra cmake -D options]
#   --target NAME   build only NAME and what it needs (repeatable; --target=NAME also works).
#                   Without it everything is built, tests and benchmarks included.
#   other arguments are passed to the cmake configure step, which then runs again.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build="${LOCALIZER_BUILD_DIR:-$root/build}"
jobs="$(nproc 2>/dev/null || echo 2)"
cmake_args=()
target_args=()
while [ $# -gt 0 ]; do
  case "$1" in
    --target)
      [ $# -ge 2 ] && [ -n "$2" ] || { echo "deploy/build.sh: --target needs a target name" >&2; exit 2; }
      target_args+=(--target "$2")
      shift 2
      ;;
    --target=*)
      [ -n "${1#--target=}" ] || { echo "deploy/build.sh: --target= needs a target name" >&2; exit 2; }
      target_args+=(--target "${1#--target=}")
      shift
      ;;
    *)
      cmake_args+=("$1")
      shift
      ;;
  esac
done
# ${a[@]+"${a[@]}"}: an empty array expands to nothing under set -u on any bash.
if [ ! -f "$build/CMakeCache.txt" ] || [ ${#cmake_args[@]} -gt 0 ]; then
  cmake -S "$root" -B "$build" -DCMAKE_BUILD_TYPE=Release ${cmake_args[@]+"${cmake_args[@]}"}
fi
cmake --build "$build" -j "$jobs" ${target_args[@]+"${target_args[@]}"}
