#!/usr/bin/env bash
# Runs on the lent GPU machine from the repository root (see pack_for_device.sh): every GPU
# test, then the benchmarks; full logs under $OUT, a summary at the end of the output.
set -uo pipefail
here=.device
export LD_LIBRARY_PATH="$PWD/$here/lib:/usr/local/cuda/lib64:${LD_LIBRARY_PATH:-}"
out=${OUT:-/tmp/out}
mkdir -p "$out"
nvidia-smi --query-gpu=name,driver_version,memory.total --format=csv | tee "$out/device.txt"
status=0
for t in "$here"/bin/*_test; do
  name=$(basename "$t")
  "$t" --gtest_brief=1 >"$out/$name.log" 2>&1 || status=1
  echo "$name: $(grep -E '^\[  (PASSED|FAILED|SKIPPED) ' "$out/$name.log" | tr '\n' ' ')"
done
for b in gpu_gcc_bench gpu_pf_bench; do
  [[ -x "$here/bin/$b" ]] && "$here/bin/$b" 2>&1 | tee "$out/$b.log"
done
"$here/bin/gpu_sessions_bench" --backend gpu --offline --seconds 4 2>&1 | tee "$out/offline_gpu.log"
"$here/bin/gpu_sessions_bench" --backend cpu --offline --seconds 4 2>&1 | tee "$out/offline_cpu.log"
"$here/bin/gpu_sessions_bench" --backend gpu --sessions 500,1000,2000,3000 --seconds 3 2>&1 |
  tee "$out/sessions.log"
exit $status
