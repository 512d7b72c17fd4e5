// Launchers for the two kernels of the batched SRP-PHAT (srp_kernels.cu), which srp_batch.cc
// drives:
//
//   spectra ──LaunchSrpMap──▶ map (z per grid direction) ──LaunchSrpPeak──▶ arg-max, refined peak
//
// Plain C++ (no Eigen, no engine headers with Eigen): the descriptors are POD structs that
// srp_batch.cc fills from each array's configuration and uploads. All pointers are device
// pointers; each launch is asynchronous on `stream` and returns the launch error as a Status
// (execution errors surface at the next synchronisation). Spectra are interleaved (re, im)
// floats, bit-compatible with cufftComplex.
#pragma once

#include <cuda_runtime_api.h>

#include <cstdint>

#include "engine/core/status.h"
#include "gpu/srp/srp_math.cuh"

namespace localizer::gpu {

// One array (geometry, band, direction grid) that sessions of a batch may share.
struct SrpArrayDesc {
  srp::SrpBand band;
  int32_t pairs = 0;
  int32_t directions = 0;          // grid size D
  int32_t refine = 0;              // 1: Newton's method from the arg-max (srp_math.cuh)
  double z_per_power = 0.0;        // 1 / (B sigma sqrt(P)): the map is written as the CPU's z
  int64_t directions_offset = 0;   // first direction in the batch's table (3 floats each)
  int64_t lag_offset = 0;          // first D_p in the float table (3 floats per pair)
  srp::RefineGeometry geometry;    // its lag_per_direction: D_p in double, device memory
};

// One session's frame in a batch.
struct SrpSessionTask {
  int32_t array = 0;
  int32_t pad = 0;
  int64_t spectra_offset = 0;  // first float of its P x B complex values (pair-major)
  int64_t map_offset = 0;      // first float of its D map values
};

// What the peak kernel found for one session.
struct SrpSessionResult {
  double ux = 0.0, uy = 0.0, uz = 0.0;  // refined direction (sphere, plane); the grid's without refine
  double theta_rad = 0.0;               // refined cone angle (linear arrays)
  double z = 0.0;                       // the CPU's z at the refined direction (refine), else grid z
  float grid_z = 0.0f;                  // the map's largest value
  int32_t grid_index = -1;              // its direction (first maximum); -1: the map had no number
  int32_t iterations = 0;               // Newton iterations taken (0 without refine)
  int32_t probes = 0;                   // spectrum probes (value, gradient, Hessian) evaluated
};

struct SrpMapArgs {
  const SrpArrayDesc* arrays = nullptr;
  const SrpSessionTask* tasks = nullptr;
  const float* spectra = nullptr;
  const float* directions = nullptr;         // 3 floats per direction, unit vectors
  const float* lag_per_direction = nullptr;  // 3 floats per pair (D_p)
  float* map = nullptr;
  int sessions = 0;
  int max_directions = 0;        // the largest grid of the batch's arrays
  int max_spectrum_floats = 0;   // the largest 2 P B of the batch's arrays
  int max_pairs = 0;
};
// One block of kMapThreads threads per (session, kMapThreads directions); the block stages the
// session's spectra and D_p in shared memory (2 P B + 3 P floats: needs cudaFuncSetAttribute
// beyond 48 KiB, which srp_batch.cc makes at Create through SrpMapSharedBytes/PrepareSrpMap).
constexpr int kSrpMapThreads = 256;
Status LaunchSrpMap(const SrpMapArgs& args, cudaStream_t stream);
// The shared memory a map launch needs, and raising the kernel's limit to the device's opt-in
// maximum (INVALID_ARGUMENT when even that is less than shared_bytes).
int SrpMapSharedBytes(int max_spectrum_floats, int max_pairs);
Status PrepareSrpMap(int shared_bytes);

struct SrpPeakArgs {
  const SrpArrayDesc* arrays = nullptr;
  const SrpSessionTask* tasks = nullptr;
  const float* spectra = nullptr;
  const float* directions = nullptr;
  const float* map = nullptr;
  SrpSessionResult* results = nullptr;
  int sessions = 0;
};
// One warp per session: the map's arg-max, then (refine) Newton's method on the session's exact
// spectrum in double, the warp's lanes splitting each pair's bins.
Status LaunchSrpPeak(const SrpPeakArgs& args, cudaStream_t stream);

}  // namespace localizer::gpu
