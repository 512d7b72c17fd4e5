// The kernels of the batched SRP-PHAT (see srp_kernels.h for what each computes; the maths is
// srp_math.cuh, which tests/gpu/srp_math_test.cu runs on the host against the CPU SrpPhat).
// Deterministic by construction: each map value is one thread's sum in a fixed order, the
// arg-max combines (value, index) pairs by an order-independent rule, and the refinement's
// lane sums are reduced in a fixed tree and broadcast from lane 0, so every lane of a warp
// takes the same branches. No atomics.
// nvcc's front end flags engine/core/status.h's assignment of a [[nodiscard]] Status to a
// member as "ignoring return value" (g++ does not); the engine code is fine.
#pragma nv_diag_suppress 2810
#include <cstddef>
#include <string>

#include "gpu/core/cuda_status.h"
#include "gpu/srp/srp_kernels.h"

namespace localizer::gpu {
namespace {

constexpr int kPeakThreads = 128;  // 4 sessions per block, a warp each
constexpr int kWarp = 32;
constexpr unsigned kFullMask = 0xffffffffu;

__global__ void __launch_bounds__(kSrpMapThreads) SrpMapKernel(SrpMapArgs a) {
  extern __shared__ float shared[];
  const SrpSessionTask task = a.tasks[blockIdx.x];
  const SrpArrayDesc& array = a.arrays[task.array];
  const int first = blockIdx.y * kSrpMapThreads;
  if (first >= array.directions) return;  // the whole block: this array's grid is smaller
  // The session's spectra and D_p, read by every thread of the block at the same addresses
  // (shared-memory broadcasts).
  const int spectrum_floats = 2 * array.pairs * array.band.bins;
  float* g = shared;
  float* lags = shared + a.max_spectrum_floats;
  const float* in = a.spectra + task.spectra_offset;
  for (int i = threadIdx.x; i < spectrum_floats; i += kSrpMapThreads) g[i] = in[i];
  for (int i = threadIdx.x; i < 3 * array.pairs; i += kSrpMapThreads) lags[i] = a.lag_per_direction[array.lag_offset + i];
  __syncthreads();
  const int d = first + threadIdx.x;
  if (d >= array.directions) return;
  const float* u = a.directions + 3 * (array.directions_offset + d);
  const float power = srp::SteeredPower<float>(g, lags, array.pairs, array.band, u[0], u[1], u[2]);
  a.map[task.map_offset + d] = power * static_cast<float>(array.z_per_power);
}

// A warp's sum of one pair's LagSums: each lane sums its bins (stride 32), a fixed tree adds
// the lanes into lane 0, and lane 0's sums go to every lane.
struct WarpPairSums {
  const float* spectra;  // the session's, in global memory
  srp::SrpBand band;
  int lane;
  __device__ srp::LagSums operator()(int pair, double lag_samples) const {
    srp::LagSums v =
        srp::PairLagSums(spectra + 2 * static_cast<std::ptrdiff_t>(pair) * band.bins, band, lag_samples, lane, kWarp);
    for (int offset = kWarp / 2; offset > 0; offset /= 2) {
      v.r += __shfl_down_sync(kFullMask, v.r, offset);
      v.dr += __shfl_down_sync(kFullMask, v.dr, offset);
      v.d2r += __shfl_down_sync(kFullMask, v.d2r, offset);
    }
    v.r = __shfl_sync(kFullMask, v.r, 0);
    v.dr = __shfl_sync(kFullMask, v.dr, 0);
    v.d2r = __shfl_sync(kFullMask, v.d2r, 0);
    return v;
  }
};

__global__ void __launch_bounds__(kPeakThreads) SrpPeakKernel(SrpPeakArgs a) {
  const int session = (blockIdx.x * kPeakThreads + threadIdx.x) / kWarp;
  const int lane = threadIdx.x % kWarp;
  if (session >= a.sessions) return;  // whole warps: sessions are warp-aligned
  const SrpSessionTask task = a.tasks[session];
  const SrpArrayDesc& array = a.arrays[task.array];
  const float* map = a.map + task.map_offset;
  srp::MapPeak best = srp::NoMapPeak();
  for (int d = lane; d < array.directions; d += kWarp) best = srp::BetterMapPeak(best, {map[d], d});
  // BetterMapPeak is a total order, so the butterfly leaves every lane with the same winner.
  for (int offset = kWarp / 2; offset > 0; offset /= 2) {
    srp::MapPeak other;
    other.value = __shfl_xor_sync(kFullMask, best.value, offset);
    other.index = __shfl_xor_sync(kFullMask, best.index, offset);
    best = srp::BetterMapPeak(best, other);
  }
  SrpSessionResult result;
  if (best.index >= array.directions) {  // no value compared as a number (NaN map)
    if (lane == 0) {
      result.grid_index = -1;
      result.z = result.grid_z = __int_as_float(0x7fc00000);
      a.results[session] = result;
    }
    return;
  }
  const float* u = a.directions + 3 * (array.directions_offset + best.index);
  result.grid_index = best.index;
  result.grid_z = best.value;
  const srp::RefineCell cell = srp::StartCell(u, array.geometry.axis);
  result.ux = cell.u.x;
  result.uy = cell.u.y;
  result.uz = cell.u.z;
  result.theta_rad = cell.theta_rad;
  result.z = best.value;
  if (array.refine != 0) {
    WarpPairSums sums{a.spectra + task.spectra_offset, array.band, lane};
    const srp::RefineResult refined = srp::RefineDirection(array.geometry, cell, sums);
    result.ux = refined.cell.u.x;
    result.uy = refined.cell.u.y;
    result.uz = refined.cell.u.z;
    result.theta_rad = refined.cell.theta_rad;
    // z = sum_p R_p / (sigma sqrt(P)) = value B z_per_power.
    result.z = refined.value * array.band.bins * array.z_per_power;
    result.iterations = refined.iterations;
    result.probes = refined.probes;
  }
  if (lane == 0) a.results[session] = result;
}

}  // namespace

int SrpMapSharedBytes(int max_spectrum_floats, int max_pairs) {
  return static_cast<int>(sizeof(float)) * (max_spectrum_floats + 3 * max_pairs);
}

Status PrepareSrpMap(int shared_bytes) {
  int device = 0;
  LOCALIZER_CUDA_RETURN_IF_ERROR(cudaGetDevice(&device), "cudaGetDevice");
  int limit = 0;
  LOCALIZER_CUDA_RETURN_IF_ERROR(cudaDeviceGetAttribute(&limit, cudaDevAttrMaxSharedMemoryPerBlockOptin, device),
                                 "cudaDeviceGetAttribute(shared memory)");
  if (shared_bytes > limit) {
    return InvalidArgument("the SRP map needs " + std::to_string(shared_bytes) +
                           " bytes of shared memory per block for one session's spectra, more than the device's " +
                           std::to_string(limit) + " (fewer pairs or a narrower band)");
  }
  // The kernel's limit is process-wide: raise it to the device's whole opt-in, never to one
  // batch's need, so that creating a batch of smaller arrays cannot break a larger one's launches.
  LOCALIZER_CUDA_RETURN_IF_ERROR(
      cudaFuncSetAttribute(SrpMapKernel, cudaFuncAttributeMaxDynamicSharedMemorySize, limit),
      "cudaFuncSetAttribute(SrpMapKernel)");
  return Status::Ok();
}

Status LaunchSrpMap(const SrpMapArgs& args, cudaStream_t stream) {
  if (args.sessions == 0 || args.max_directions == 0) return Status::Ok();
  const dim3 grid(static_cast<unsigned>(args.sessions),
                  static_cast<unsigned>((args.max_directions + kSrpMapThreads - 1) / kSrpMapThreads));
  const int shared = SrpMapSharedBytes(args.max_spectrum_floats, args.max_pairs);
  SrpMapKernel<<<grid, kSrpMapThreads, shared, stream>>>(args);
  LOCALIZER_LAUNCH_RETURN_IF_ERROR("SrpMapKernel");
  return Status::Ok();
}

Status LaunchSrpPeak(const SrpPeakArgs& args, cudaStream_t stream) {
  if (args.sessions == 0) return Status::Ok();
  const int blocks = (args.sessions * kWarp + kPeakThreads - 1) / kPeakThreads;
  SrpPeakKernel<<<blocks, kPeakThreads, 0, stream>>>(args);
  LOCALIZER_LAUNCH_RETURN_IF_ERROR("SrpPeakKernel");
  return Status::Ok();
}

}  // namespace localizer::gpu
