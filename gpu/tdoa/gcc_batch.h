// GCC-PHAT for many frames at once on the GPU: frames of one batch key (gcc_plan.h), from any
// number of sessions, go through one launch sequence with ONE batched R2C and ONE batched C2R
// cuFFT execution, and come back as engine::Measurement values equal to what
// engine::GccPhatEstimator::Estimate gives for each frame alone (see gcc_phat.h for the maths).
//
// The sequence on the batch's own stream, for M frames of C channels (P = C - 1 pairs):
//   1. one small descriptor per (frame, pair) (weighting, band, L_p, interpolation, ...),
//      one source per frame and one append per ring job go to the device in small copies;
//      the frames stay in page-locked host memory (the job's own when frame_pinned, else
//      the batch's staging, into which the host copies what the device will read)
//   2. append (ring jobs, see GccJob::ring): each channel's new samples read in place over
//      the bus into the session's device ring; then pack: each channel read in place over
//      the bus (a ring job's from its ring, on the device), zero padded to N, its energy
//      (sum of squares, double). frame_sources.cuh holds both kernels' index maths.
//   3. R2C of N over M x C rows (cuFFT, batched)
//   4. weigh, per (frame, pair): G = W X_k conj(X_r) B with the CPU's weighting and floors,
//      and S = sum of |G| over the full spectrum
//   5. C2R of N over M x P rows (cuFFT, batched)
//   6. peak, per (frame, pair): R = IFFT(G) / S over lags -(L_p + 8)..(L_p + 8), first
//      maximum over |lag| <= L_p, sub-sample refinement and its floor, quality, peak value
//   7. moments, per (frame, pair): G recomputed from the spectra (C2R overwrote it), rotated
//      to the measured delay, the four sums behind delay_sigma and the candidates' spacing
//   8. results and (with keep_gcc) the GCC windows, K = 8 lags wider either side, back to
//      pinned memory in two copies
// and the host fills each job's Measurement, delay_sigma_s and candidates by the CPU's own
// functions (engine/tdoa/delay_statistics.h) from the device's moments and window.
// Agreement with the CPU: every step but the FFTs is the CPU's arithmetic (the engine's own
// functions, engine/tdoa/gcc_math.h and peak_math.h, compiled for the device;
// tests/gpu/gcc_math_test.cu checks it on the host), so only cuFFT's rounding against FFTW's
// (~1e-6 relative) separates them; tests/gpu/gcc_batch_test.cc holds delays to 1e-3 sample,
// quality, peak value, SNR and delay_sigma to 1e-3 relative, the candidates' delays to 1e-3
// sample, GCC windows to 1e-4 absolute. Within one bucket (below), a frame's results
// do not depend on the other frames: rows are transformed and reduced independently. Across
// buckets that rests on cuFFT computing a row alike whatever the batch count
// (gcc_batch_test.cc ResultsDoNotDependOnTheBatchBucket checks it on the device).
//
// Batch sizes: cuFFT plans fix their batch count, so the batch holds one plan pair per
// bucket b = 1, 2, 4, ... (powers of two, and max_frames itself), made on first use; a Run of
// n frames uses the smallest bucket >= n and zero-fills the b - n unused frames, whose
// results are dropped. At most ~2x the transform work of an exact-size plan, and no plan is
// made per call once each bucket has been seen. The plans share one cuFFT work area, sized
// to the largest of them.
//
// Bytes over the bus: a plain job brings channels * frame_samples floats; a ring job only its
// new samples (a 50 % hop halves the stage's input traffic), and the frame it reads back is
// bit-identical to the job's frame, so every result is the same either way.
//
// Memory (device), about max_frames * (C (2N + 2) + P (2N + 2)) * 4 bytes, plus pinned host
// max_frames * C * F * 4 bytes (F = frame_samples) for staging frames that are not pinned
// already; e.g. C = 4, F = 4096, N = 5120:
// ~290 KiB device + 64 KiB pinned per frame of capacity (1024 frames: ~290 MiB + 64 MiB),
// plus the cuFFT work area. GCC window buffers (device and pinned) grow to the largest
// batch's windows. Rings are the sessions' own (sample_ring.h), not the batch's.
//
// Not thread-safe: one thread runs a batch at a time (a dispatcher owns it). Run blocks the
// calling thread until the results are on the host.
#pragma once

#include <memory>
#include <span>
#include <vector>

#include "engine/core/measurement.h"
#include "engine/core/status.h"
#include "gpu/tdoa/gcc_pair_measurement.h"
#include "gpu/tdoa/gcc_plan.h"
#include "gpu/tdoa/sample_ring.h"

namespace localizer::gpu {

// One frame to measure.
struct GccJob {
  const GccPlan* plan = nullptr;  // the session's plan; its key must be the batch's
  const float* frame = nullptr;   // channel-major host memory: channels * frame_samples
  double t_s = 0.0;               // copied into out->t_s (the frame centre)
  // Filled as GccPhatEstimator::Estimate fills it; with keep_gcc off the candidates hold the
  // main peak alone (the batch returns no window to find the others in).
  engine::Measurement* out = nullptr;
  // Optional: this job's own outcome. OK, or INVALID_ARGUMENT "channel c holds a non-finite
  // sample (NaN or Inf)" (the CPU's message), in which case *out is untouched.
  Status* status = nullptr;
  // The frame lies in page-locked memory from cudaMallocHost (PinnedBuffer) and stays
  // unchanged until Run returns: the device reads it in place and the batch skips its own
  // host copy (a session that stages its frame itself takes that copy off the dispatcher).
  bool frame_pinned = false;
  // Optional: the session's device ring (sample_ring.h). The job first appends the last
  // ring_new_samples of each channel of `frame` to the ring, then the frame is read from
  // the ring: only those samples cross the bus. The caller guarantees that the ring's
  // newest frame_samples - ring_new_samples samples equal the frame's first ones (bit for
  // bit; frame_overlap.h finds that count), so the frame read back is `frame` exactly.
  // ring_new_samples must be in [1, frame_samples], and frame_samples when the ring is not
  // valid; the ring needs the batch's channel count and a capacity >= frame_samples; no two
  // jobs of one Run may share a ring. Run advances the ring by ring_new_samples once the
  // launch completed, or invalidates it when the device failed.
  SampleRing* ring = nullptr;
  int ring_new_samples = 0;
  // Optional: Run leaves each pair's candidates holding the main peak alone and fills
  // (*tails)[p] for FinishCandidates (gcc_pair_measurement.h) on the caller's thread. Null:
  // Run picks them itself.
  std::vector<GccPairTail>* tails = nullptr;
};

class GccBatch {
 public:
  // Event timings of the last Run, milliseconds of device time (0 unless created with
  // collect_timing): total from the first copy's start to the last copy's end, fft the two
  // cuFFT executions alone, device the kernels and transforms between the copies.
  struct Timing {
    float total_ms = 0.0f;
    float fft_ms = 0.0f;
    float device_ms = 0.0f;
  };

  // Device buffers, pinned staging, a stream and (lazily) cuFFT plans for up to max_frames
  // frames of `key`. INVALID_ARGUMENT for a key without a frame, fewer than 2 channels,
  // fft_size < frame_samples or max_frames outside [1, 65536]; RESOURCE_EXHAUSTED when
  // device or pinned memory runs out; FAILED_PRECONDITION without a usable device.
  // collect_timing records CUDA events around the stages (a few microseconds per Run).
  static StatusOr<std::unique_ptr<GccBatch>> Create(const GccPlan::BatchKey& key, int max_frames,
                                                    bool collect_timing = false);
  ~GccBatch();
  GccBatch(const GccBatch&) = delete;
  GccBatch& operator=(const GccBatch&) = delete;

  // Measures every job's frame. INVALID_ARGUMENT, before any work, when jobs is empty or
  // longer than max_frames, or a job has a null plan/frame/out, a plan of another key, or a
  // ring it cannot use (see GccJob::ring).
  // A CUDA or cuFFT failure returns its Status (outputs untouched). A job whose frame holds a
  // non-finite sample gets INVALID_ARGUMENT in *job.status and keeps its *out; without a
  // status pointer, Run returns that error ("job j: channel c ...") after filling the other
  // jobs. Cost: the host copies each frame that is not pinned (a ring job: its new samples)
  // once into pinned memory; the device reads that much once over the bus; the device work grows
  // with the bucket (see above). Allocates only when a new bucket's plans are made or the
  // GCC windows outgrow their buffers.
  Status Run(std::span<const GccJob> jobs);

  Timing last_timing() const;
  // Frame samples the device read from host memory in the last Run (plain jobs: the whole
  // frame; ring jobs: the new samples), in bytes: the figure the ring exists to shrink.
  std::size_t last_frame_bytes_over_bus() const;
  const GccPlan::BatchKey& key() const;
  int max_frames() const;

 private:
  struct Impl;
  explicit GccBatch(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace localizer::gpu
