#!/usr/bin/env bash
# Packs the GPU tests and benchmarks built here, with the Debian shared libraries they need,
# into .device/ (git-ignored) for the `device` tool's lent GPU machine, whose image has the
# CUDA toolkit and driver but none of our Debian packages (gRPC, FFTW, ...). CUDA's own
# libraries (cudart, cuFFT, cuRAND) are left to the machine's toolkit.
#
#   cmake --build build --target gpu_backend_test gcc_batch_test gcc_ring_test particle_bank_test \
#       particle_bank_init_test sample_ring_test gcc_ring_plan_test pf_init_builder_test gcc_math_test pf_math_test \
#       batch_queue_test srp_batch_test srp_math_test gpu_gcc_bench gpu_pf_bench gpu_srp_bench gpu_sessions_bench
#   tests/gpu/pack_for_device.sh build
# then on the device (carry [".device"]): bash .device/run.sh   (writes logs under $OUT)
set -euo pipefail
build=${1:-build}
root=$(cd "$(dirname "$0")/../.." && pwd)
out="$root/.device"
# The exclude file git reads (in a worktree, .git is a file and the file lies in the common dir).
exclude=$(git -C "$root" rev-parse --path-format=absolute --git-path info/exclude)
mkdir -p "$(dirname "$exclude")"
grep -qx '/.device/' "$exclude" 2>/dev/null || echo '/.device/' >>"$exclude"
rm -rf "$out" && mkdir -p "$out/bin" "$out/lib"
for name in gpu_backend_test gcc_batch_test gcc_ring_test particle_bank_test particle_bank_init_test \
            gcc_math_test gcc_ring_plan_test pf_math_test pf_init_builder_test batch_queue_test sample_ring_test \
            srp_batch_test srp_math_test gpu_gcc_bench gpu_pf_bench gpu_srp_bench gpu_sessions_bench; do
  missing=1
  for dir in "$build/tests" "$build/tests/bench"; do
    [[ -x "$dir/$name" ]] && cp "$dir/$name" "$out/bin/" && missing=0
  done
  # A program not built would silently drop its tests from the device run.
  [[ $missing == 0 ]] || { echo "pack_for_device: $name is not built in $build" >&2; exit 1; }
done
# Shared libraries from Debian's packages (not libc's, not CUDA's).
for bin in "$out"/bin/*; do
  ldd "$bin" | awk '/=> \// {print $3}'
done | sort -u | grep -v -E '/(libc|libm|libpthread|libdl|librt|libgcc_s|libstdc\+\+|ld-linux)[.-]' |
  grep -v -E 'libcuda|libcudart|libcufft|libcurand|libnvidia' | while read -r lib; do cp -L "$lib" "$out/lib/"; done
cp "$root/tests/gpu/device_run.sh" "$out/run.sh"
du -sh "$out"
