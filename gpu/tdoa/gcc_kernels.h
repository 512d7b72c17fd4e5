// Launchers for the three kernels of the batched GCC-PHAT stage (gcc_kernels.cu), around the
// two batched cuFFT executions that gcc_batch.cc makes:
//
//   new samples ──LaunchGccRingAppend──▶ session rings (sample_ring.cuh)
//   frames or rings ──LaunchGccPack──▶ signal, energy ──R2C──▶ spectra ──LaunchGccWeigh──▶ cross, S
//          ──C2R──▶ corr ──LaunchGccPeak──▶ results, gcc windows ──LaunchGccMoments──▶ results
//
// Plain C++ (no Eigen, no engine headers with Eigen): the descriptors are POD structs that
// gcc_batch.cc fills from each session's GccPlan and uploads with the batch. All pointers are
// device pointers; every launch is asynchronous on `stream` and returns the launch error as
// a Status (execution errors surface at the next synchronisation). Complex data is
// interleaved (re, im) float, bit-compatible with cufftComplex. Row r of a buffer of row
// length n starts at r * n; rows are (frame, channel) = frame * channels + channel for
// frames/signal/spectra/energy and (frame, pair) = task index for cross/corr/results.
#pragma once

#include <cuda_runtime_api.h>

#include <cstdint>

#include "engine/core/status.h"

namespace localizer::gpu {

// One (frame, pair) of a batch: what its session's plan says about that pair.
struct GccPairTask {
  int32_t ref_row = 0;         // spectrum row of the frame's reference channel
  int32_t sensor_row = 0;      // spectrum row of the pair's other channel
  int32_t weighting = 0;       // gcc::WeightingCode
  float beta = 0.0f;           // PHAT-beta exponent
  int32_t band_first_bin = 0;  // bins [band_first_bin, band_end_bin) are weighed; others 0
  int32_t band_end_bin = 0;
  int32_t max_lag = 0;        // L_p: lags -L_p..L_p are searched
  int32_t interpolation = 0;  // gcc::InterpolationCode
  int64_t gcc_offset = -1;    // first float of the pair's window in the gcc output; -1: none
};

// What the kernels found for one (frame, pair). delay in samples = peak_lag + offset_samples.
struct GccPairResult {
  double offset_samples = 0.0;  // sub-sample refinement, [-1, 1]
  double energy_ref = 0.0;      // sum of squares of the two channels (non-finite: NaN/Inf input)
  double energy_sensor = 0.0;
  float norm = 0.0f;        // S, sum of |G| over the full spectrum; <= 0: nothing measured
  float peak_value = 0.0f;  // R at the integer peak
  float quality = 0.0f;     // peak over largest sidelobe (gcc_phat.h), capped at 1e9
  int32_t peak_lag = 0;     // integer lag of the peak, samples
  // The refinement's floor for delay_sigma (engine::InterpolationErrorSamples) and the
  // moments of G at the delay (engine::SpectrumMoments; LaunchGccMoments).
  double floor_samples = 0.0;
  double level = 0.0;
  double first = 0.0;
  double curvature = 0.0;
  double slope_var = 0.0;
};

// Where one frame's samples are: channel c's row starts at samples + c * row_samples and the
// frame's i-th sample is at row index ring::Wrap(first, i, row_samples). A frame in host
// memory: row_samples = frame_samples, first = 0 (never wraps). A frame in a session's device
// ring: row_samples = the ring's capacity, first = where the frame starts in it.
struct GccFrameSource {
  const float* samples = nullptr;
  int32_t row_samples = 0;
  int32_t first = 0;
  int32_t taper_edge = 0;  // samples tapered at each end (engine/tdoa/gcc_math.h's TaperGain)
};

// rows = padded_frames * channels rows of fft_size floats: row r < live_rows gets frame row
// r (frame_samples floats, times the frame's taper) then zeros; rows >= live_rows get zeros.
// energy[r] = sum of squares of row r in double, by a fixed-order block reduction. The
// values, hence every result, are the same whether a frame is read from the host or from a
// ring.
struct GccPackArgs {
  // Per live frame, where it lies: page-locked host memory that the device reads in place
  // (cudaMallocHost: mapped at the same address under unified addressing, so no separate
  // host-to-device copy of the frame is needed), or a session's device ring.
  const GccFrameSource* sources = nullptr;
  float* signal = nullptr;   // rows * fft_size
  double* energy = nullptr;  // rows
  int live_rows = 0;         // live frames * channels
  int rows = 0;
  int channels = 0;
  int frame_samples = 0;
  int fft_size = 0;
};
Status LaunchGccPack(const GccPackArgs& args, cudaStream_t stream);

// One session's append to its ring: per channel c, source sample source_first + i of the
// channel's row (row length source_row_samples, page-locked host memory read in place) goes
// to ring row index ring::Wrap(write_first, i, capacity), i in [0, count): a
// ring::RingJobPlan's append. Runs before the pack of the same batch.
struct GccRingAppend {
  const float* source = nullptr;  // host, channel-major
  float* ring = nullptr;          // device, channels rows of capacity
  int32_t source_row_samples = 0;
  int32_t source_first = 0;
  int32_t capacity = 0;
  int32_t write_first = 0;
  int32_t count = 0;
};

// One block per (append, channel).
struct GccAppendArgs {
  const GccRingAppend* appends = nullptr;  // device, append_count
  int append_count = 0;
  int channels = 0;
};
Status LaunchGccRingAppend(const GccAppendArgs& args, cudaStream_t stream);

// Per task t: cross row t = G over bins 0..N/2 (zero outside the band), results[t].norm = S,
// results[t].energy_* from energy[]. One block per task.
struct GccWeighArgs {
  const GccPairTask* tasks = nullptr;  // task_count
  const float* spectra = nullptr;      // interleaved, (N/2 + 1) complex per row
  const double* energy = nullptr;      // per spectrum row
  float* cross = nullptr;              // interleaved, (N/2 + 1) complex per task
  GccPairResult* results = nullptr;    // task_count
  int task_count = 0;
  int fft_size = 0;
};
Status LaunchGccWeigh(const GccWeighArgs& args, cudaStream_t stream);

// Per task t, from corr row t (the unnormalised C2R output, lag l at index l mod N) and
// results[t].norm: the peak, its refinement, its floor, quality and peak value into
// results[t], and R = corr / S at lags -(L + K)..L + K (K = engine::kPeakHalfWidth: the
// candidates' refinement reads past the searched lags) into gcc[tasks[t].gcc_offset ..] when
// that is >= 0. A task with S <= 0 gets peak_lag 0, offset 0, peak 0, quality 0 and an
// all-zero window. One block per task.
struct GccPeakArgs {
  const GccPairTask* tasks = nullptr;
  const float* corr = nullptr;       // task_count rows of fft_size
  GccPairResult* results = nullptr;  // norm in, the rest out
  float* gcc = nullptr;              // windows of tasks with gcc_offset >= 0
  int task_count = 0;
  int fft_size = 0;
};
Status LaunchGccPeak(const GccPeakArgs& args, cudaStream_t stream);

// Per task t with S > 0, after the peak: G recomputed from the spectra as LaunchGccWeigh
// weighs it (the C2R has overwritten cross), rotated to the delay peak_lag + offset_samples,
// its moments into results[t] (level, first, curvature, slope_var). cuFFT's C2R destroys its
// input, and recomputing costs less than keeping a copy of every cross row. One block per task.
struct GccMomentsArgs {
  const GccPairTask* tasks = nullptr;
  const float* spectra = nullptr;    // as GccWeighArgs
  GccPairResult* results = nullptr;  // energies, norm, peak in; moments out
  int task_count = 0;
  int fft_size = 0;
};
Status LaunchGccMoments(const GccMomentsArgs& args, cudaStream_t stream);

}  // namespace localizer::gpu
