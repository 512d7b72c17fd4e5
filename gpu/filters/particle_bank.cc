#include "gpu/filters/particle_bank.h"

#include <cuda_runtime_api.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <mutex>
#include <string>
#include <utility>

#include "gpu/core/cuda_status.h"
#include "gpu/core/device.h"
#include "gpu/core/device_buffer.h"
#include "gpu/filters/init_builder.h"
#include "gpu/filters/pf_kernels.h"
#include "gpu/filters/slot_layout.h"
#include "gpu/filters/step_builder.h"

namespace localizer::gpu {
namespace {

constexpr std::size_t kStagingAlign = 256;

std::size_t AlignUp(std::size_t x) { return (x + kStagingAlign - 1) / kStagingAlign * kStagingAlign; }

// Grows a staging buffer to at least `count` elements, with a quarter to spare so a slowly
// growing batch does not reallocate every Step.
template <typename Buffer>
Status Grow(Buffer& buffer, std::size_t count) {
  if (buffer.size() >= count) return Status::Ok();
  return buffer.Reserve(count + count / 4);
}

struct Slot {
  pf::SessionConfig config;
  pf::SlotLayout layout;
  DeviceBuffer<unsigned char> memory;
  int current = 0;               // which state buffer is current
  unsigned long long draws = 0;  // Philox windows used so far
  bool initialised = false;
  double ess = 0.0;  // after the last update
  pf::SlotView View() const { return layout.View(memory.data(), current); }
};

}  // namespace

struct ParticleBank::Impl {
  Impl(std::size_t limit_bytes, CudaStream s) : limit(limit_bytes), stream(std::move(s)) {}

  const std::size_t limit;
  CudaStream stream;
  mutable std::mutex mutex;
  // Everything below is guarded by `mutex`.
  std::size_t in_use = 0;
  std::vector<std::unique_ptr<Slot>> slots;  // nullptr: a free number
  // Step staging, grown on demand.
  PinnedBuffer<unsigned char> host_in;
  DeviceBuffer<unsigned char> device_in;
  DeviceBuffer<pf::SessionWork> work;
  DeviceBuffer<pf::StepOutput> device_out;
  PinnedBuffer<pf::StepOutput> host_out;
  std::vector<pf::SessionStep> steps;
  std::vector<int> block_request;
  std::vector<float> gcc;
  std::vector<std::size_t> launched;  // request index of each descriptor
  std::vector<char> seen;
  // Batched initialisation staging (its own: a Step runs right after it on the stream).
  pf::InitPlan init_plan;
  PinnedBuffer<unsigned char> init_host;
  DeviceBuffer<unsigned char> init_device;
  std::vector<std::size_t> init_launched;  // request index of each task
  std::vector<char> init_seen;
  std::vector<StepRequest> moment_requests;
  std::vector<StepResult> moment_results;

  Slot* Find(int slot) const {
    if (slot < 0 || slot >= static_cast<int>(slots.size())) return nullptr;
    return slots[static_cast<std::size_t>(slot)].get();
  }
  Status StepLocked(std::span<const StepRequest> requests, std::span<StepResult> results);
  Status Launch();
  Status LaunchInit();
};

ParticleBank::ParticleBank(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
ParticleBank::~ParticleBank() = default;

StatusOr<std::unique_ptr<ParticleBank>> ParticleBank::Create(std::size_t memory_limit_bytes) {
  const std::string& reason = DeviceUnavailableReason();
  if (!reason.empty()) return FailedPrecondition("particle bank: no usable GPU: " + reason);
  auto stream = CudaStream::Create();
  if (!stream.ok()) return stream.status();
  return std::unique_ptr<ParticleBank>(
      new ParticleBank(std::make_unique<Impl>(memory_limit_bytes, std::move(stream).value())));
}

StatusOr<int> ParticleBank::Open(const engine::ArrayGeometry& array, const engine::ParticleFilterOptions& options) {
  auto config = pf::MakeSessionConfig(array, options);
  if (!config.ok()) return config.status();
  const pf::SlotLayout layout = pf::SlotLayout::For(options.particles);
  Impl& b = *impl_;
  std::lock_guard<std::mutex> lock(b.mutex);
  const std::string wanted =
      "a slot of " + std::to_string(options.particles) + " particles needs " + std::to_string(layout.bytes) + " bytes";
  if (b.limit != 0 && b.in_use + layout.bytes > b.limit) {
    const std::size_t left = b.in_use < b.limit ? b.limit - b.in_use : 0;
    return ResourceExhausted("particle bank: " + wanted + "; " + std::to_string(left) + " of its " +
                             std::to_string(b.limit) + "-byte limit are left");
  }
  auto memory = DeviceBuffer<unsigned char>::Allocate(layout.bytes);
  if (!memory.ok()) {
    cudaGetLastError();  // a failed allocation must not surface later as a launch error
    if (memory.status().code() != StatusCode::kResourceExhausted) return memory.status();
    std::size_t free_bytes = 0, total_bytes = 0;
    cudaMemGetInfo(&free_bytes, &total_bytes);
    cudaGetLastError();
    return ResourceExhausted("particle bank: " + wanted + "; the device has " + std::to_string(free_bytes) +
                             " bytes free (" + memory.status().message() + ")");
  }
  auto slot = std::make_unique<Slot>();
  slot->config = std::move(config).value();
  slot->layout = layout;
  slot->memory = std::move(memory).value();
  std::size_t index = 0;
  while (index < b.slots.size() && b.slots[index] != nullptr) ++index;
  if (index == b.slots.size()) b.slots.emplace_back();
  b.slots[index] = std::move(slot);
  b.in_use += layout.bytes;
  return static_cast<int>(index);
}

void ParticleBank::Close(int slot) {
  Impl& b = *impl_;
  std::lock_guard<std::mutex> lock(b.mutex);
  Slot* s = b.Find(slot);
  if (s == nullptr) return;
  b.in_use -= s->layout.bytes;
  b.slots[static_cast<std::size_t>(slot)].reset();  // cudaFree: Step is synchronous, nothing in flight
}

Status ParticleBank::InitialiseGaussian(int slot, const engine::Vec6& mean, const engine::Mat6& root) {
  if (!mean.allFinite() || !root.allFinite()) return InvalidArgument("initial mean or root is not finite");
  Impl& b = *impl_;
  std::lock_guard<std::mutex> lock(b.mutex);
  Slot* s = b.Find(slot);
  if (s == nullptr) return InvalidArgument("particle bank: slot " + std::to_string(slot) + " is not open");
  pf::GaussianInit init{};
  LOCALIZER_RETURN_IF_ERROR(pf::MakeGaussianInit(s->config, mean, root, s->draws + 1, &init));
  ++s->draws;
  cudaGetLastError();  // errors of earlier calls were reported by those calls
  LOCALIZER_RETURN_IF_ERROR(pf::LaunchInitialiseGaussian(s->View(), init, b.stream.get()));
  LOCALIZER_RETURN_IF_ERROR(b.stream.Synchronize());
  s->initialised = true;
  s->ess = s->config.options.particles;
  return Status::Ok();
}

Status ParticleBank::InitialiseRegion(int slot, const engine::Vec3& min_m, const engine::Vec3& max_m,
                                      double speed_sigma_mps) {
  if (!min_m.allFinite() || !max_m.allFinite() || (max_m - min_m).minCoeff() < 0.0 || !(speed_sigma_mps >= 0.0) ||
      !std::isfinite(speed_sigma_mps)) {
    return InvalidArgument("initial region must be a finite box with min <= max and speed sigma >= 0");
  }
  Impl& b = *impl_;
  std::lock_guard<std::mutex> lock(b.mutex);
  Slot* s = b.Find(slot);
  if (s == nullptr) return InvalidArgument("particle bank: slot " + std::to_string(slot) + " is not open");
  pf::RegionInit init{};
  LOCALIZER_RETURN_IF_ERROR(pf::MakeRegionInit(s->config, min_m, max_m, speed_sigma_mps, s->draws + 1, &init));
  ++s->draws;
  cudaGetLastError();
  LOCALIZER_RETURN_IF_ERROR(pf::LaunchInitialiseRegion(s->View(), init, b.stream.get()));
  LOCALIZER_RETURN_IF_ERROR(b.stream.Synchronize());
  s->initialised = true;
  s->ess = s->config.options.particles;
  return Status::Ok();
}

Status ParticleBank::Initialise(std::span<const InitRequest> requests, std::span<InitResult> results) {
  if (requests.size() != results.size()) {
    return InvalidArgument("particle bank Initialise: " + std::to_string(requests.size()) + " requests but " +
                           std::to_string(results.size()) + " results");
  }
  Impl& b = *impl_;
  std::lock_guard<std::mutex> lock(b.mutex);
  b.init_plan.Clear();
  b.init_launched.clear();
  b.init_seen.assign(b.slots.size(), 0);
  for (std::size_t q = 0; q < requests.size(); ++q) {
    const InitRequest& rq = requests[q];
    InitResult& res = results[q];
    res = InitResult{};
    Slot* s = b.Find(rq.slot);
    if (s == nullptr) {
      res.status = InvalidArgument("particle bank: slot " + std::to_string(rq.slot) + " is not open");
      continue;
    }
    if (b.init_seen[static_cast<std::size_t>(rq.slot)]) {
      res.status =
          InvalidArgument("particle bank: slot " + std::to_string(rq.slot) + " appears twice in one Initialise");
      continue;
    }
    pf::InitTask task;
    task.slot = s->View();
    task.kind = rq.region ? pf::kInitRegion : pf::kInitGaussian;
    // The slot's next Philox window, as the one-slot calls take it.
    res.status = rq.region
                     ? pf::MakeRegionInit(s->config, rq.min_m, rq.max_m, rq.speed_sigma_mps, s->draws + 1, &task.region)
                     : pf::MakeGaussianInit(s->config, rq.mean, rq.root, s->draws + 1, &task.gaussian);
    if (!res.status.ok()) continue;
    ++s->draws;
    b.init_seen[static_cast<std::size_t>(rq.slot)] = 1;
    b.init_plan.Add(task);
    b.init_launched.push_back(q);
  }
  if (b.init_launched.empty()) return Status::Ok();

  const Status launch = b.LaunchInit();
  if (!launch.ok()) {
    (void)b.stream.Synchronize();  // whatever was enqueued finishes before the staging is reused
    for (std::size_t q : b.init_launched) {
      results[q].status = launch;
      b.Find(requests[q].slot)->initialised = false;  // its particles may be half written
    }
    return launch;
  }
  // The moments of every initialised slot: one predict-only Step over all of them, queued
  // behind the initialisation on the same stream (its synchronisation waits for both).
  b.moment_requests.clear();
  for (std::size_t q : b.init_launched) {
    Slot& s = *b.Find(requests[q].slot);
    s.initialised = true;
    s.ess = s.config.options.particles;
    b.moment_requests.push_back({requests[q].slot, 0.0, nullptr, nullptr, nullptr});
  }
  b.moment_results.resize(b.moment_requests.size());
  const Status moments = b.StepLocked(b.moment_requests, b.moment_results);
  for (std::size_t k = 0; k < b.init_launched.size(); ++k) {
    InitResult& res = results[b.init_launched[k]];
    res.status = moments.ok() ? b.moment_results[k].status : moments;
    res.state = b.moment_results[k].state;
  }
  return moments;
}

Status ParticleBank::Step(std::span<const StepRequest> requests, std::span<StepResult> results) {
  if (requests.size() != results.size()) {
    return InvalidArgument("particle bank Step: " + std::to_string(requests.size()) + " requests but " +
                           std::to_string(results.size()) + " results");
  }
  std::lock_guard<std::mutex> lock(impl_->mutex);
  return impl_->StepLocked(requests, results);
}

StatusOr<engine::TrackState> ParticleBank::Moments(int slot) {
  const StepRequest request{slot, 0.0, nullptr, nullptr, nullptr};
  StepResult result;
  std::lock_guard<std::mutex> lock(impl_->mutex);
  LOCALIZER_RETURN_IF_ERROR(impl_->StepLocked({&request, 1}, {&result, 1}));
  if (!result.status.ok()) return result.status;
  return result.state;
}

std::size_t ParticleBank::bytes_in_use() const {
  std::lock_guard<std::mutex> lock(impl_->mutex);
  return impl_->in_use;
}

std::size_t ParticleBank::memory_limit_bytes() const { return impl_->limit; }

int ParticleBank::open_slots() const {
  std::lock_guard<std::mutex> lock(impl_->mutex);
  return static_cast<int>(std::count_if(impl_->slots.begin(), impl_->slots.end(),
                                        [](const std::unique_ptr<Slot>& s) { return s != nullptr; }));
}

Status ParticleBank::Impl::StepLocked(std::span<const StepRequest> requests, std::span<StepResult> results) {
  steps.clear();
  block_request.clear();
  gcc.clear();
  launched.clear();
  seen.assign(slots.size(), 0);
  for (std::size_t q = 0; q < requests.size(); ++q) {
    const StepRequest& rq = requests[q];
    StepResult& res = results[q];
    res = StepResult{};
    Slot* slot = Find(rq.slot);
    if (slot == nullptr) {
      res.status = InvalidArgument("particle bank: slot " + std::to_string(rq.slot) + " is not open");
      continue;
    }
    if (seen[static_cast<std::size_t>(rq.slot)]) {
      res.status = InvalidArgument("particle bank: slot " + std::to_string(rq.slot) + " appears twice in one Step");
      continue;
    }
    if (!slot->initialised) {
      res.status =
          FailedPrecondition("particle bank: slot " + std::to_string(rq.slot) + " stepped before initialisation");
      continue;
    }
    pf::SessionStep step{};
    const std::size_t gcc_before = gcc.size();
    res.status = pf::FillSessionStep(slot->config, {rq.dt_s, rq.measurement, rq.used, rq.sigmas_s}, &gcc, &step);
    if (!res.status.ok()) {
      gcc.resize(gcc_before);
      continue;
    }
    seen[static_cast<std::size_t>(rq.slot)] = 1;
    step.slot = slot->View();
    step.first_block = static_cast<int>(block_request.size());
    step.prior_ess = slot->ess;
    if (step.do_predict || step.do_update) step.draw = ++slot->draws;
    block_request.insert(block_request.end(), static_cast<std::size_t>(slot->layout.blocks),
                         static_cast<int>(steps.size()));
    steps.push_back(step);
    launched.push_back(q);
  }
  if (steps.empty()) return Status::Ok();

  const Status launch = Launch();
  if (!launch.ok()) {
    for (std::size_t q : launched) results[q].status = launch;
    return launch;
  }
  for (std::size_t k = 0; k < steps.size(); ++k) {
    const std::size_t q = launched[k];
    const StepRequest& rq = requests[q];
    StepResult& res = results[q];
    Slot& slot = *Find(rq.slot);
    const pf::StepOutput& o = host_out.data()[k];
    for (int r = 0; r < 6; ++r) {
      res.state.mean(r) = o.mean[r] + (r < 3 ? slot.config.origin_m[r] : 0.0);
      for (int c = 0; c < 6; ++c) res.state.covariance(r, c) = o.cov[r * 6 + c];
    }
    res.ess = o.ess;
    res.resampled = o.resampled != 0;
    res.cholesky_fallback = o.cholesky_fallback != 0;
    res.innovations.assign(static_cast<std::size_t>(slot.config.pairs), engine::InnovationMoments{});
    if (steps[k].do_update) {
      for (int p = 0; p < slot.config.pairs; ++p) {
        if (!rq.used[p]) continue;
        const double sigma_s = rq.sigmas_s[p];
        const double mean_e = o.sum_e[p];
        const double var = std::max(0.0, o.sum_e2[p] - mean_e * mean_e);
        res.innovations[static_cast<std::size_t>(p)].mean_s = mean_e * sigma_s;
        res.innovations[static_cast<std::size_t>(p)].predicted_var_s2 = var * sigma_s * sigma_s;
      }
      slot.ess = o.ess;
    }
    if (res.resampled) slot.current ^= 1;
  }
  return Status::Ok();
}

// Copies the plan's tasks and block table in (one H2D) and enqueues the batched
// initialisation; does not wait (the moments' Step that follows on the stream does).
Status ParticleBank::Impl::LaunchInit() {
  const std::size_t tasks = init_plan.tasks.size();
  const std::size_t blocks_at = AlignUp(tasks * sizeof(pf::InitTask));
  const std::size_t bytes = blocks_at + init_plan.block_task.size() * sizeof(int);
  LOCALIZER_RETURN_IF_ERROR(Grow(init_host, bytes));
  LOCALIZER_RETURN_IF_ERROR(Grow(init_device, bytes));
  unsigned char* in = init_host.data();
  std::memcpy(in, init_plan.tasks.data(), tasks * sizeof(pf::InitTask));
  std::memcpy(in + blocks_at, init_plan.block_task.data(), init_plan.block_task.size() * sizeof(int));
  cudaGetLastError();  // errors of earlier calls were reported by those calls
  const cudaStream_t s = stream.get();
  LOCALIZER_CUDA_RETURN_IF_ERROR(cudaMemcpyAsync(init_device.data(), in, bytes, cudaMemcpyHostToDevice, s),
                                 "cudaMemcpyAsync(particle bank initialisation)");
  pf::InitLaunch launch;
  launch.tasks = reinterpret_cast<const pf::InitTask*>(init_device.data());
  launch.block_task = reinterpret_cast<const int*>(init_device.data() + blocks_at);
  launch.blocks = init_plan.blocks();
  return pf::LaunchInitialiseBatch(launch, s);
}

// Copies the descriptors, block table and GCC windows in (one H2D), runs the kernels, copies
// the outputs back (one D2H) and waits.
Status ParticleBank::Impl::Launch() {
  const std::size_t requests = steps.size();
  const std::size_t blocks_at = AlignUp(requests * sizeof(pf::SessionStep));
  const std::size_t gcc_at = AlignUp(blocks_at + block_request.size() * sizeof(int));
  const std::size_t input_bytes = gcc_at + gcc.size() * sizeof(float);
  LOCALIZER_RETURN_IF_ERROR(Grow(host_in, input_bytes));
  LOCALIZER_RETURN_IF_ERROR(Grow(device_in, input_bytes));
  LOCALIZER_RETURN_IF_ERROR(Grow(work, requests));
  LOCALIZER_RETURN_IF_ERROR(Grow(device_out, requests));
  LOCALIZER_RETURN_IF_ERROR(Grow(host_out, requests));
  unsigned char* in = host_in.data();
  std::memcpy(in, steps.data(), requests * sizeof(pf::SessionStep));
  std::memcpy(in + blocks_at, block_request.data(), block_request.size() * sizeof(int));
  if (!gcc.empty()) std::memcpy(in + gcc_at, gcc.data(), gcc.size() * sizeof(float));
  cudaGetLastError();  // errors of earlier calls were reported by those calls
  const cudaStream_t s = stream.get();
  LOCALIZER_CUDA_RETURN_IF_ERROR(cudaMemcpyAsync(device_in.data(), in, input_bytes, cudaMemcpyHostToDevice, s),
                                 "cudaMemcpyAsync(particle bank step inputs)");
  pf::StepLaunch launch;
  launch.steps = reinterpret_cast<const pf::SessionStep*>(device_in.data());
  launch.block_request = reinterpret_cast<const int*>(device_in.data() + blocks_at);
  launch.gcc = reinterpret_cast<const float*>(device_in.data() + gcc_at);
  launch.work = work.data();
  launch.out = device_out.data();
  launch.requests = static_cast<int>(requests);
  launch.blocks = static_cast<int>(block_request.size());
  LOCALIZER_RETURN_IF_ERROR(pf::LaunchStep(launch, s));
  LOCALIZER_CUDA_RETURN_IF_ERROR(
      cudaMemcpyAsync(host_out.data(), device_out.data(), requests * sizeof(pf::StepOutput), cudaMemcpyDeviceToHost, s),
      "cudaMemcpyAsync(particle bank step outputs)");
  return stream.Synchronize();
}

}  // namespace localizer::gpu
