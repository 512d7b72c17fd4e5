#!/usr/bin/env bash
# Runs on the lent GPU machine from the repository root (see pack_for_device.sh): every GPU
# test, the kernels under compute-sanitizer, then the benchmarks; full logs under $OUT, a
# summary at the end of the output. Each step has its own time limit so that one hang
# cannot eat the call.
#   bash .device/run.sh [tests|sanitize|bench|all]   (default all)
set -uo pipefail
here=.device
what=${1:-all}
export LD_LIBRARY_PATH="$PWD/$here/lib:/usr/local/cuda/lib64:${LD_LIBRARY_PATH:-}"
out=${OUT:-/tmp/out}
mkdir -p "$out"
nvidia-smi --query-gpu=name,driver_version,memory.total,clocks.sm,clocks.max.sm --format=csv |
  tee "$out/device.txt"
status=0
missing=$(ldd "$here"/bin/* 2>/dev/null | grep 'not found' | sort -u)
[[ -n "$missing" ]] && { echo "missing libraries:"; echo "$missing"; }
if [[ $what == all || $what == tests ]]; then
  for t in "$here"/bin/*_test; do
    name=$(basename "$t")
    timeout 120 "$t" --gtest_brief=1 >"$out/$name.log" 2>&1 || status=1
    echo "$name: $(grep -E '^\[  (PASSED|FAILED|SKIPPED) |^\[  FAILED  \]' "$out/$name.log" | tr '\n' ' ')"
    grep -B2 -A8 -E 'Failure|error' "$out/$name.log" | head -40
  done
fi
if [[ $what == all || $what == sanitize ]]; then
  sanitizer=$(command -v compute-sanitizer || ls /usr/local/cuda/bin/compute-sanitizer 2>/dev/null)
  for t in gcc_batch_test gcc_ring_test particle_bank_test particle_bank_init_test gpu_backend_test srp_batch_test; do
    [[ -x "$here/bin/$t" && -n "$sanitizer" ]] || continue
    timeout 150 "$sanitizer" --tool memcheck --leak-check no --error-exitcode 3 \
      "$here/bin/$t" --gtest_brief=1 >"$out/memcheck_$t.log" 2>&1 || status=1
    echo "memcheck $t: $(grep -E 'ERROR SUMMARY|PASSED|FAILED' "$out/memcheck_$t.log" | tr '\n' ' ')"
  done
fi
if [[ $what == all || $what == bench ]]; then
  for b in gpu_gcc_bench gpu_pf_bench gpu_srp_bench; do
    [[ -x "$here/bin/$b" ]] && timeout 120 "$here/bin/$b" 2>&1 | tee "$out/$b.log"
  done
  timeout 60 "$here/bin/gpu_sessions_bench" --backend gpu --offline --seconds 4 2>&1 | tee "$out/offline_gpu.log"
  timeout 60 "$here/bin/gpu_sessions_bench" --backend cpu --offline --seconds 4 2>&1 | tee "$out/offline_cpu.log"
  # Every session starting in one hop (a burst no service sees), then starts spread over 3 s.
  for stagger in 0 3; do
    timeout 300 "$here/bin/gpu_sessions_bench" --backend gpu --sessions ${SESSIONS:-1000,2000,3000,4000} \
      --seconds ${AUDIO_S:-6} --stagger-s $stagger 2>&1 | tee -a "$out/sessions.log"
  done
fi
exit $status
