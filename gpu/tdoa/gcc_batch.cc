#include "gpu/tdoa/gcc_batch.h"

#include <cuda_runtime_api.h>
#include <cufft.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <map>
#include <span>
#include <string>
#include <unordered_set>
#include <utility>
#include <vector>

#include "engine/tdoa/peak_interpolation.h"
#include "gpu/core/cuda_status.h"
#include "gpu/core/device.h"
#include "gpu/core/device_buffer.h"
#include "gpu/tdoa/cuda_handles.h"
#include "gpu/tdoa/frame_sources.cuh"
#include "gpu/tdoa/gcc_kernels.h"
#include "gpu/tdoa/gcc_math.cuh"

namespace localizer::gpu {
namespace {

// The descriptor's codes are the engine's enums as integers.
static_assert(static_cast<int>(engine::Weighting::kPhat) == gcc::kPhat);
static_assert(static_cast<int>(engine::Weighting::kPhatBeta) == gcc::kPhatBeta);
static_assert(static_cast<int>(engine::Weighting::kScot) == gcc::kScot);
static_assert(static_cast<int>(engine::Weighting::kCc) == gcc::kCc);
static_assert(static_cast<int>(engine::PeakInterpolation::kParabolic) == gcc::kParabolic);
static_assert(static_cast<int>(engine::PeakInterpolation::kGaussian) == gcc::kGaussian);
static_assert(static_cast<int>(engine::PeakInterpolation::kSinc) == gcc::kSinc);
static_assert(sizeof(cufftComplex) == 2 * sizeof(float));

constexpr int kMaxFramesLimit = 1 << 16;

// Milliseconds between two recorded, completed events.
StatusOr<float> Elapsed(const CudaEvent& from, const CudaEvent& to) {
  float ms = 0.0f;
  LOCALIZER_CUDA_RETURN_IF_ERROR(cudaEventElapsedTime(&ms, from.get(), to.get()), "cudaEventElapsedTime");
  return ms;
}

// Smallest power of two >= n, capped at max_frames (itself a bucket).
int BucketFor(int n, int max_frames) {
  int bucket = 1;
  while (bucket < n) bucket <<= 1;
  return bucket < max_frames ? bucket : max_frames;
}

template <typename T>
Status AllocateInto(std::size_t count, T* buffer) {
  auto allocated = T::Allocate(count);
  if (!allocated.ok()) return allocated.status();
  *buffer = std::move(allocated).value();
  return Status::Ok();
}

// Grows a device/pinned pair to `count` elements (contents not kept).
template <typename T>
Status ReservePair(std::size_t count, DeviceBuffer<T>* device, PinnedBuffer<T>* host) {
  LOCALIZER_RETURN_IF_ERROR(device->Reserve(count));
  return host->Reserve(count);
}

// A ring job's ring and count against GccJob::ring's contract; `rings` collects the rings
// seen so far in the Run.
Status CheckRingJob(const GccJob& job, const GccBatchKey& key, const std::string& which,
                    std::unordered_set<const SampleRing*>* rings) {
  const SampleRing& r = *job.ring;
  const int fresh = job.ring_new_samples;
  if (r.data() == nullptr || r.channels() != key.channels || r.capacity() < key.frame_samples) {
    return InvalidArgument(which + "'s ring has " + std::to_string(r.channels()) + " channels x " +
                           std::to_string(r.capacity()) + " samples; the batch needs " + std::to_string(key.channels) +
                           " channels x at least " + std::to_string(key.frame_samples));
  }
  if (fresh < 1 || fresh > key.frame_samples) {
    return InvalidArgument(which + " brings " + std::to_string(fresh) + " new ring samples; must be in [1, " +
                           std::to_string(key.frame_samples) + "]");
  }
  if (r.total() + fresh < key.frame_samples) {
    return InvalidArgument(which + " brings " + std::to_string(fresh) + " new samples to a ring holding " +
                           std::to_string(r.total()) + (r.valid() ? "" : " (not valid)") + "; a frame needs " +
                           std::to_string(key.frame_samples));
  }
  if (!rings->insert(&r).second) return InvalidArgument(which + "'s ring is already used by another job of the batch");
  return Status::Ok();
}

}  // namespace

struct GccBatch::Impl {
  struct FftPlans {
    CufftPlan forward;  // R2C over bucket * channels rows
    CufftPlan inverse;  // C2R over bucket * pairs rows
  };
  enum Mark { kStart, kCopiedIn, kR2cStart, kR2cEnd, kC2rStart, kC2rEnd, kKernelsDone, kEnd, kMarks };

  Status Init();
  StatusOr<FftPlans*> PlansFor(int bucket);
  Status Enqueue(std::span<const GccJob> jobs, int bucket, std::size_t gcc_floats);
  Status Record(Mark mark);
  Status ReadTiming();
  void Fill(const GccJob& job, int frame, Status* first_error);

  GccBatchKey key;
  int max_frames = 0;
  bool collect_timing = false;
  int channels = 0;
  int pairs = 0;
  int bins = 0;

  CudaStream stream;
  PinnedBuffer<float> staged_frames;            // max_frames * channels * frame_samples
  PinnedBuffer<GccFrameSource> staged_sources;  // max_frames: where each frame lies
  PinnedBuffer<GccRingAppend> staged_appends;   // max_frames: the ring jobs' appends
  PinnedBuffer<GccPairTask> staged_tasks;
  PinnedBuffer<GccPairResult> staged_results;
  PinnedBuffer<float> staged_gcc;  // grows to the largest batch's windows
  // Fill's scratch for the candidates of jobs that leave them to the batch.
  std::vector<GccPairTail> own_tails;
  std::vector<engine::WindowExtremum> extrema;
  DeviceBuffer<GccFrameSource> sources;
  DeviceBuffer<GccRingAppend> appends;
  DeviceBuffer<GccPairTask> tasks;
  DeviceBuffer<double> energy;          // max_frames * channels
  DeviceBuffer<float> signal;           // max_frames * channels * N
  DeviceBuffer<float> spectra;          // max_frames * channels * (N/2 + 1) complex
  DeviceBuffer<float> cross;            // max_frames * pairs * (N/2 + 1) complex
  DeviceBuffer<float> corr;             // max_frames * pairs * N
  DeviceBuffer<GccPairResult> results;  // max_frames * pairs
  DeviceBuffer<float> gcc;
  DeviceBuffer<char> work_area;   // shared by every plan (they run one after another)
  std::map<int, FftPlans> plans;  // by bucket
  std::vector<CudaEvent> marks;   // kMarks events with collect_timing, else none
  Timing timing;
  std::size_t frame_bytes_over_bus = 0;  // of the last Run
};

Status GccBatch::Impl::Init() {
  channels = key.channels;
  pairs = channels - 1;
  bins = key.fft_size / 2 + 1;
  const std::size_t frames_max = static_cast<std::size_t>(max_frames);
  const std::size_t rows = frames_max * channels;
  const std::size_t pair_rows = frames_max * pairs;
  auto created = CudaStream::Create();
  if (!created.ok()) return created.status();
  stream = std::move(created).value();
  LOCALIZER_RETURN_IF_ERROR(AllocateInto(rows * key.frame_samples, &staged_frames));
  LOCALIZER_RETURN_IF_ERROR(AllocateInto(pair_rows, &staged_tasks));
  LOCALIZER_RETURN_IF_ERROR(AllocateInto(pair_rows, &staged_results));
  LOCALIZER_RETURN_IF_ERROR(AllocateInto(frames_max, &staged_sources));
  LOCALIZER_RETURN_IF_ERROR(AllocateInto(frames_max, &staged_appends));
  LOCALIZER_RETURN_IF_ERROR(AllocateInto(frames_max, &sources));
  LOCALIZER_RETURN_IF_ERROR(AllocateInto(frames_max, &appends));
  LOCALIZER_RETURN_IF_ERROR(AllocateInto(pair_rows, &tasks));
  LOCALIZER_RETURN_IF_ERROR(AllocateInto(rows, &energy));
  LOCALIZER_RETURN_IF_ERROR(AllocateInto(rows * key.fft_size, &signal));
  LOCALIZER_RETURN_IF_ERROR(AllocateInto(rows * 2 * bins, &spectra));
  LOCALIZER_RETURN_IF_ERROR(AllocateInto(pair_rows * 2 * bins, &cross));
  LOCALIZER_RETURN_IF_ERROR(AllocateInto(pair_rows * key.fft_size, &corr));
  LOCALIZER_RETURN_IF_ERROR(AllocateInto(pair_rows, &results));
  if (collect_timing) {
    for (int i = 0; i < kMarks; ++i) {
      auto event = CudaEvent::Create();
      if (!event.ok()) return event.status();
      marks.push_back(std::move(event).value());
    }
  }
  // The largest bucket now: its work area bounds the others', and a batch too large for the
  // device fails here rather than on the first full Run.
  auto largest = PlansFor(max_frames);
  return largest.ok() ? Status::Ok() : largest.status();
}

StatusOr<GccBatch::Impl::FftPlans*> GccBatch::Impl::PlansFor(int bucket) {
  auto found = plans.find(bucket);
  if (found != plans.end()) return &found->second;
  std::size_t forward_work = 0;
  std::size_t inverse_work = 0;
  auto forward =
      CufftPlan::Make(key.fft_size, CUFFT_R2C, static_cast<long long>(bucket) * channels, stream.get(), &forward_work);
  if (!forward.ok()) return forward.status();
  auto inverse =
      CufftPlan::Make(key.fft_size, CUFFT_C2R, static_cast<long long>(bucket) * pairs, stream.get(), &inverse_work);
  if (!inverse.ok()) return inverse.status();
  // The previous Run has completed (Run synchronises), so the old area may be freed.
  LOCALIZER_RETURN_IF_ERROR(work_area.Reserve(std::max(forward_work, inverse_work)));
  FftPlans& made = plans[bucket];
  made.forward = std::move(forward).value();
  made.inverse = std::move(inverse).value();
  return &made;
}

Status GccBatch::Impl::Record(Mark mark) {
  if (!collect_timing) return Status::Ok();
  return FromCuda(cudaEventRecord(marks[mark].get(), stream.get()), "cudaEventRecord");
}

Status GccBatch::Impl::ReadTiming() {
  if (!collect_timing) return Status::Ok();
  auto total = Elapsed(marks[kStart], marks[kEnd]);
  auto r2c = Elapsed(marks[kR2cStart], marks[kR2cEnd]);
  auto c2r = Elapsed(marks[kC2rStart], marks[kC2rEnd]);
  auto device = Elapsed(marks[kCopiedIn], marks[kKernelsDone]);
  for (const auto* t : {&total, &r2c, &c2r, &device}) {
    if (!t->ok()) return t->status();
  }
  timing = {*total, *r2c + *c2r, *device};
  return Status::Ok();
}

// Stages the jobs' frames and descriptors and enqueues the whole sequence on the stream.
Status GccBatch::Impl::Enqueue(std::span<const GccJob> jobs, int bucket, std::size_t gcc_floats) {
  const int count = static_cast<int>(jobs.size());
  const std::size_t frame_floats = static_cast<std::size_t>(channels) * key.frame_samples;
  const int task_count = count * pairs;
  const std::size_t spectrum_floats = 2 * static_cast<std::size_t>(bins);

  auto found_plans = PlansFor(bucket);
  if (!found_plans.ok()) return found_plans.status();
  FftPlans& fft = **found_plans;
  LOCALIZER_RETURN_IF_ERROR(ReservePair(gcc_floats, &gcc, &staged_gcc));

  std::int64_t gcc_offset = 0;
  int append_count = 0;
  frame_bytes_over_bus = 0;
  for (int j = 0; j < count; ++j) {
    const GccJob& job = jobs[j];
    const GccPlan& plan = *job.plan;
    // What the device reads from the host: each channel's last `fresh` samples.
    const int fresh = job.ring != nullptr ? job.ring_new_samples : key.frame_samples;
    const float* host = job.frame;
    if (!job.frame_pinned) {
      float* staged = staged_frames.data() + j * frame_floats;
      StageNewSamples(job.frame, staged, channels, key.frame_samples, fresh);
      host = staged;
    }
    frame_bytes_over_bus += sizeof(float) * static_cast<std::size_t>(channels) * fresh;
    if (job.ring == nullptr) {
      staged_sources.data()[j] = WholeFrameSource(host, key.frame_samples);
    } else {
      const SampleRing& r = *job.ring;
      const RingJobDescriptors d = DescribeRingJob(host, r.data(), r.capacity(), r.total(), key.frame_samples, fresh);
      staged_appends.data()[append_count++] = d.append;
      staged_sources.data()[j] = d.source;
    }
    const engine::GccOptions& options = plan.options();
    const engine::GccLayout& layout = plan.layout();
    staged_sources.data()[j].taper_edge =
        engine::TaperEdgeSamples(key.frame_samples, static_cast<float>(options.taper_fraction));
    for (int p = 0; p < pairs; ++p) {
      GccPairTask& t = staged_tasks.data()[j * pairs + p];
      t.ref_row = j * channels + plan.reference_sensor();
      t.sensor_row = j * channels + plan.sensor_of_pair(p);
      t.weighting = static_cast<int32_t>(options.weighting);
      t.beta = static_cast<float>(options.phat_beta);
      t.band_first_bin = layout.band_first_bin;
      t.band_end_bin = layout.band_end_bin;
      t.max_lag = layout.max_lag_samples[p];
      t.interpolation = static_cast<int32_t>(options.interpolation);
      t.gcc_offset = options.keep_gcc ? gcc_offset : -1;
      if (options.keep_gcc) gcc_offset += 2 * static_cast<std::int64_t>(t.max_lag + engine::kPeakHalfWidth) + 1;
    }
  }

  cudaStream_t s = stream.get();
  LOCALIZER_RETURN_IF_ERROR(Record(kStart));
  LOCALIZER_CUDA_RETURN_IF_ERROR(
      cudaMemcpyAsync(sources.data(), staged_sources.data(), sizeof(GccFrameSource) * count, cudaMemcpyHostToDevice, s),
      "cudaMemcpyAsync(frame sources)");
  if (append_count > 0) {
    LOCALIZER_CUDA_RETURN_IF_ERROR(cudaMemcpyAsync(appends.data(), staged_appends.data(),
                                                   sizeof(GccRingAppend) * append_count, cudaMemcpyHostToDevice, s),
                                   "cudaMemcpyAsync(ring appends)");
  }
  LOCALIZER_CUDA_RETURN_IF_ERROR(
      cudaMemcpyAsync(tasks.data(), staged_tasks.data(), sizeof(GccPairTask) * task_count, cudaMemcpyHostToDevice, s),
      "cudaMemcpyAsync(tasks)");
  LOCALIZER_RETURN_IF_ERROR(Record(kCopiedIn));

  GccAppendArgs append;
  append.appends = appends.data();
  append.append_count = append_count;
  append.channels = channels;
  LOCALIZER_RETURN_IF_ERROR(LaunchGccRingAppend(append, s));

  GccPackArgs pack;
  pack.sources = sources.data();
  pack.signal = signal.data();
  pack.energy = energy.data();
  pack.live_rows = count * channels;
  pack.rows = bucket * channels;
  pack.channels = channels;
  pack.frame_samples = key.frame_samples;
  pack.fft_size = key.fft_size;
  LOCALIZER_RETURN_IF_ERROR(LaunchGccPack(pack, s));

  LOCALIZER_RETURN_IF_ERROR(Record(kR2cStart));
  if (work_area.data() != nullptr) {
    LOCALIZER_CUFFT_RETURN_IF_ERROR(cufftSetWorkArea(fft.forward.get(), work_area.data()), "cufftSetWorkArea(R2C)");
  }
  LOCALIZER_CUFFT_RETURN_IF_ERROR(
      cufftExecR2C(fft.forward.get(), signal.data(), reinterpret_cast<cufftComplex*>(spectra.data())), "cufftExecR2C");
  LOCALIZER_RETURN_IF_ERROR(Record(kR2cEnd));

  GccWeighArgs weigh;
  weigh.tasks = tasks.data();
  weigh.spectra = spectra.data();
  weigh.energy = energy.data();
  weigh.cross = cross.data();
  weigh.results = results.data();
  weigh.task_count = task_count;
  weigh.fft_size = key.fft_size;
  LOCALIZER_RETURN_IF_ERROR(LaunchGccWeigh(weigh, s));
  if (bucket > count) {  // the padding frames' rows: zero, as their signal rows are
    const std::size_t live = spectrum_floats * task_count;
    const std::size_t padded = spectrum_floats * (static_cast<std::size_t>(bucket) * pairs);
    LOCALIZER_CUDA_RETURN_IF_ERROR(cudaMemsetAsync(cross.data() + live, 0, sizeof(float) * (padded - live), s),
                                   "cudaMemsetAsync(cross padding)");
  }

  LOCALIZER_RETURN_IF_ERROR(Record(kC2rStart));
  if (work_area.data() != nullptr) {
    LOCALIZER_CUFFT_RETURN_IF_ERROR(cufftSetWorkArea(fft.inverse.get(), work_area.data()), "cufftSetWorkArea(C2R)");
  }
  LOCALIZER_CUFFT_RETURN_IF_ERROR(
      cufftExecC2R(fft.inverse.get(), reinterpret_cast<cufftComplex*>(cross.data()), corr.data()), "cufftExecC2R");
  LOCALIZER_RETURN_IF_ERROR(Record(kC2rEnd));

  GccPeakArgs peak;
  peak.tasks = tasks.data();
  peak.corr = corr.data();
  peak.results = results.data();
  peak.gcc = gcc.data();
  peak.task_count = task_count;
  peak.fft_size = key.fft_size;
  LOCALIZER_RETURN_IF_ERROR(LaunchGccPeak(peak, s));
  GccMomentsArgs moments;
  moments.tasks = tasks.data();
  moments.spectra = spectra.data();
  moments.results = results.data();
  moments.task_count = task_count;
  moments.fft_size = key.fft_size;
  LOCALIZER_RETURN_IF_ERROR(LaunchGccMoments(moments, s));
  LOCALIZER_RETURN_IF_ERROR(Record(kKernelsDone));

  LOCALIZER_CUDA_RETURN_IF_ERROR(cudaMemcpyAsync(staged_results.data(), results.data(),
                                                 sizeof(GccPairResult) * task_count, cudaMemcpyDeviceToHost, s),
                                 "cudaMemcpyAsync(results)");
  if (gcc_floats > 0) {
    LOCALIZER_CUDA_RETURN_IF_ERROR(
        cudaMemcpyAsync(staged_gcc.data(), gcc.data(), sizeof(float) * gcc_floats, cudaMemcpyDeviceToHost, s),
        "cudaMemcpyAsync(gcc)");
  }
  return Record(kEnd);
}

// Job `frame`'s results into its Measurement, as GccPhatEstimator::Estimate fills one; a
// frame with a non-finite sample is reported instead (lowest channel first, as the CPU).
void GccBatch::Impl::Fill(const GccJob& job, int frame, Status* first_error) {
  const GccPlan& plan = *job.plan;
  const GccPairResult* r = staged_results.data() + static_cast<std::size_t>(frame) * pairs;
  for (int c = 0; c < channels; ++c) {
    // Channel c's energy: the reference's is in every pair, another's in its own pair.
    double e = 0.0;
    if (c == plan.reference_sensor()) {
      e = r[0].energy_ref;
    } else {
      for (int p = 0; p < pairs; ++p) {
        if (plan.sensor_of_pair(p) == c) e = r[p].energy_sensor;
      }
    }
    if (!std::isfinite(e)) {
      Status bad = InvalidArgument("channel " + std::to_string(c) + " holds a non-finite sample (NaN or Inf)");
      if (job.status != nullptr) {
        *job.status = std::move(bad);
      } else if (first_error->ok()) {
        *first_error = InvalidArgument("job " + std::to_string(frame) + ": " + bad.message());
      }
      return;
    }
  }
  engine::Measurement* out = job.out;
  out->t_s = job.t_s;
  out->sample_rate_hz = plan.options().sample_rate_hz;
  out->window_time_var_s2 = plan.layout().window_time_var_s2;
  out->pairs.resize(pairs);
  std::vector<GccPairTail>& tails = job.tails != nullptr ? *job.tails : own_tails;
  tails.resize(static_cast<std::size_t>(pairs));
  for (int p = 0; p < pairs; ++p) {
    const GccPairTask& task = staged_tasks.data()[static_cast<std::size_t>(frame) * pairs + p];
    const float* window = task.gcc_offset >= 0 ? staged_gcc.data() + task.gcc_offset : nullptr;
    FillPairMeasurement(plan, p, r[p], window, &tails[p], &out->pairs[p]);
  }
  if (job.tails == nullptr) FinishCandidates(plan, tails, out, &extrema);
  if (job.status != nullptr) *job.status = Status::Ok();
}

GccBatch::GccBatch(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
GccBatch::~GccBatch() = default;

StatusOr<std::unique_ptr<GccBatch>> GccBatch::Create(const GccPlan::BatchKey& key, int max_frames,
                                                     bool collect_timing) {
  if (key.frame_samples < 1 || key.channels < 2 || key.fft_size < key.frame_samples) {
    return InvalidArgument("GCC batch key " + key.ToString() +
                           " needs frame_samples >= 1, channels >= 2 and fft_size >= frame_samples");
  }
  if (max_frames < 1 || max_frames > kMaxFramesLimit) {
    return InvalidArgument("GCC batch max_frames is " + std::to_string(max_frames) + "; must be in [1, " +
                           std::to_string(kMaxFramesLimit) + "]");
  }
  if (const std::string& reason = DeviceUnavailableReason(); !reason.empty()) {
    return FailedPrecondition("no usable GPU for the GCC batch: " + reason);
  }
  auto impl = std::make_unique<Impl>();
  impl->key = key;
  impl->max_frames = max_frames;
  impl->collect_timing = collect_timing;
  LOCALIZER_RETURN_IF_ERROR(impl->Init());
  return std::unique_ptr<GccBatch>(new GccBatch(std::move(impl)));
}

Status GccBatch::Run(std::span<const GccJob> jobs) {
  Impl& s = *impl_;
  if (jobs.empty() || static_cast<int>(jobs.size()) > s.max_frames) {
    return InvalidArgument("GCC batch of " + std::to_string(jobs.size()) + " jobs; must be 1.." +
                           std::to_string(s.max_frames));
  }
  std::size_t gcc_floats = 0;
  std::unordered_set<const SampleRing*> rings;
  for (std::size_t j = 0; j < jobs.size(); ++j) {
    const GccJob& job = jobs[j];
    const std::string which = "GCC batch job " + std::to_string(j);
    if (job.plan == nullptr || job.frame == nullptr || job.out == nullptr) {
      return InvalidArgument(which + " has a null plan, frame or out");
    }
    if (!(job.plan->key() == s.key)) {
      return InvalidArgument(which + " has key " + job.plan->key().ToString() + "; the batch's is " + s.key.ToString());
    }
    gcc_floats += job.plan->gcc_floats();
    if (job.ring != nullptr) LOCALIZER_RETURN_IF_ERROR(CheckRingJob(job, s.key, which, &rings));
  }
  const int count = static_cast<int>(jobs.size());
  // The rings' contents are unknown once the device failed after their appends may have run.
  const auto invalidate_rings = [&] {
    for (const GccJob& job : jobs) {
      if (job.ring != nullptr) job.ring->Invalidate();
    }
  };
  const Status enqueued = s.Enqueue(jobs, BucketFor(count, s.max_frames), gcc_floats);
  if (!enqueued.ok()) {
    // Whatever was enqueued must finish before the staging buffers are written again.
    (void)s.stream.Synchronize();
    invalidate_rings();
    return enqueued;
  }
  if (Status done = s.stream.Synchronize(); !done.ok()) {
    invalidate_rings();
    return done;
  }
  // Every append ran (a frame with a non-finite sample is appended too: the ring mirrors the
  // stream, whatever its job's outcome).
  for (const GccJob& job : jobs) {
    if (job.ring != nullptr) job.ring->Advance(job.ring_new_samples);
  }
  LOCALIZER_RETURN_IF_ERROR(s.ReadTiming());
  Status first_error;
  for (int j = 0; j < count; ++j) s.Fill(jobs[j], j, &first_error);
  return first_error;
}

GccBatch::Timing GccBatch::last_timing() const { return impl_->timing; }
std::size_t GccBatch::last_frame_bytes_over_bus() const { return impl_->frame_bytes_over_bus; }
const GccPlan::BatchKey& GccBatch::key() const { return impl_->key; }
int GccBatch::max_frames() const { return impl_->max_frames; }

}  // namespace localizer::gpu
