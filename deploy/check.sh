#!/usr/bin/env bash
# Fuzz check (docs/FUZZING.md; docs/DEVELOPMENT.md): builds the libFuzzer targets of
# tests/fuzz with the `fuzz` preset (clang, ASan + UBSan, build-fuzz/), writes their seed
# corpora, and runs each target for a fixed time, printing its executions and exit status.
# Optionally runs the sanitizer test suites too (deploy/sanitize.sh asan, tsan).
# Incremental and idempotent: the build is incremental, the seeds are rewritten, and each
# target's working corpus (build-fuzz/tests/fuzz/work/<target>) is kept and grows between runs.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"

usage() {
  cat <<'USAGE'
usage: deploy/check.sh [--seconds N] [--only TARGET[,TARGET...]] [--runs N] [--sanitize]
                       [--no-build] [--list] [--help]

  --seconds N   fuzz each target for N seconds (default 60)
  --runs N      stop a target after N executions instead (libFuzzer -runs; --seconds still caps it)
  --only LIST   run only these targets (comma separated, e.g. fuzz_scan,fuzz_wav)
  --sanitize    afterwards also run deploy/sanitize.sh asan and deploy/sanitize.sh tsan
  --no-build    use the fuzz build already in build-fuzz/
  --list        print the fuzz targets and exit
  --help        this text

Prints one line per target: executions, seconds, exec/s, status (ok, or FOUND with the
crash file under build-fuzz/tests/fuzz/artifacts/<target>/). Exit status 1 when any target
found something (or a sanitizer suite failed), 2 for a usage error.
Environment: LOCALIZER_JOBS (build jobs; default nproc), LOCALIZER_CMAKE_ARGS (extra configure
options, e.g. "-DCMAKE_CXX_COMPILER_LAUNCHER=ccache"), FUZZ_NICE (nice level of the fuzzers; default 10).
USAGE
}

targets=(fuzz_session_config fuzz_track_stream fuzz_sample_block fuzz_imu_batch fuzz_scan fuzz_locate_request
         fuzz_array_json fuzz_csv_readers fuzz_wav fuzz_room_scene)
# Largest input per target: whole protos and files up to 1 MiB; the proto decoders' cost
# grows with the input, so larger adds time, not coverage.
declare -A max_len=([fuzz_array_json]=65536 [fuzz_csv_readers]=65536 [fuzz_wav]=262144 [fuzz_room_scene]=65536)
# fuzz_wav: Debian's libsndfile hands MP3-like input to libmpg123, which writes several lines to
# stderr for every malformed frame (about 9 per execution, some 200 MB of log a minute). libFuzzer's
# -close_fd_mask=2 closes the target's stderr; libFuzzer's own lines and the sanitizer reports go
# to a duplicate of it, so the log keeps the progress, the statistics and any finding.
declare -A extra_flags=([fuzz_wav]=-close_fd_mask=2)

seconds=60
runs=-1
only=""
sanitize=0
build=1
while [ $# -gt 0 ]; do
  case "$1" in
    --seconds) seconds="${2:?--seconds needs a number}"; shift 2 ;;
    --runs) runs="${2:?--runs needs a number}"; shift 2 ;;
    --only) only="${2:?--only needs a list}"; shift 2 ;;
    --sanitize) sanitize=1; shift ;;
    --no-build) build=0; shift ;;
    --list) printf '%s\n' "${targets[@]}"; exit 0 ;;
    --help|-h) usage; exit 0 ;;
    *) echo "deploy/check.sh: unknown option $1" >&2; usage >&2; exit 2 ;;
  esac
done
case "$seconds" in ''|*[!0-9]*) echo "--seconds must be a whole number" >&2; exit 2 ;; esac
case "$runs" in -1) ;; ''|*[!0-9]*) echo "--runs must be a whole number" >&2; exit 2 ;; esac
if [ -n "$only" ]; then
  IFS=, read -r -a selected <<<"$only"
  for t in "${selected[@]}"; do
    case " ${targets[*]} " in *" $t "*) ;; *) echo "unknown target $t (see --list)" >&2; exit 2 ;; esac
  done
  targets=("${selected[@]}")
fi

cd "$root"
jobs="${LOCALIZER_JOBS:-$(nproc 2>/dev/null || echo 2)}"
dir=build-fuzz/tests/fuzz
if [ "$build" = 1 ]; then
  if [ ! -f build-fuzz/CMakeCache.txt ]; then
    # shellcheck disable=SC2086  # LOCALIZER_CMAKE_ARGS is a list of options
    cmake --preset fuzz ${LOCALIZER_CMAKE_ARGS:-}
  fi
  cmake --build --preset fuzz -j "$jobs"
fi
for t in "${targets[@]}"; do
  [ -x "$dir/$t" ] || { echo "$dir/$t is missing: build the fuzz preset (drop --no-build)" >&2; exit 1; }
done
# One writer at a time: two check.sh runs side by side (two targets on two cores) would
# otherwise share the seed writer's scratch folder.
flock "$dir/.seeds.lock" "$dir/fuzz_seeds" "$dir/corpus" >/dev/null

failed=0
printf '%-22s %12s %8s %10s  %s\n' target executions seconds exec/s status
for t in "${targets[@]}"; do
  mkdir -p "$dir/work/$t" "$dir/artifacts/$t" "$dir/logs"
  log="$dir/logs/$t.log"
  extra=()
  if [ -n "${extra_flags[$t]:-}" ]; then extra=("${extra_flags[$t]}"); fi
  start=$(date +%s)
  set +e
  # -max_total_time bounds the run; -timeout and -rss_limit_mb make a hang or a blow-up a finding.
  nice -n "${FUZZ_NICE:-10}" "$dir/$t" "$dir/work/$t" "$dir/corpus/$t" \
    -max_total_time="$seconds" -runs="$runs" -max_len="${max_len[$t]:-1048576}" -timeout=10 -rss_limit_mb=2048 \
    -print_final_stats=1 -artifact_prefix="$dir/artifacts/$t/" "${extra[@]}" >"$log" 2>&1
  rc=$?
  set -e
  elapsed=$(( $(date +%s) - start ))
  execs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log" | tail -1)
  rate=$(sed -n 's/^stat::average_exec_per_sec: *//p' "$log" | tail -1)
  status=ok
  if [ "$rc" != 0 ]; then
    status="FOUND (exit $rc; $log)"
    failed=1
  fi
  printf '%-22s %12s %8s %10s  %s\n' "$t" "${execs:-?}" "$elapsed" "${rate:-?}" "$status"
done

if [ "$sanitize" = 1 ]; then
  bash deploy/sanitize.sh asan || failed=1
  bash deploy/sanitize.sh tsan || failed=1
fi
exit "$failed"
