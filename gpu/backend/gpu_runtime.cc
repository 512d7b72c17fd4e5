#include "gpu/backend/gpu_runtime.h"

#include <cuda_runtime_api.h>

#include <chrono>
#include <map>
#include <vector>

#include "gpu/core/cuda_status.h"
#include "gpu/core/device.h"

namespace localizer::gpu {
namespace {

// The bank's share of the device when the options leave it open: 3/4 of what is free now,
// leaving room for cuFFT work areas and the GCC batches.
StatusOr<std::size_t> DefaultBankLimit() {
  std::size_t free_bytes = 0, total_bytes = 0;
  LOCALIZER_CUDA_RETURN_IF_ERROR(cudaMemGetInfo(&free_bytes, &total_bytes), "cudaMemGetInfo");
  return free_bytes / 4 * 3;
}

}  // namespace

StatusOr<std::shared_ptr<GpuRuntime>> GpuRuntime::Create(const GpuBackendOptions& options) {
  LOCALIZER_RETURN_IF_ERROR(options.Validate());
  if (!DeviceUnavailableReason().empty()) return FailedPrecondition(DeviceUnavailableReason());
  std::size_t limit = options.bank_limit_bytes;
  if (limit == 0) {
    auto fallback = DefaultBankLimit();
    if (!fallback.ok()) return fallback.status();
    limit = *fallback;
  }
  std::shared_ptr<GpuRuntime> runtime(new GpuRuntime(options));
  auto bank = ParticleBank::Create(limit);
  if (!bank.ok()) return bank.status();
  runtime->bank_ = std::move(bank).value();
  const auto window =
      std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::duration<double>(options.batch_window_s));
  GpuRuntime* self = runtime.get();
  runtime->gcc_queue_ = std::make_unique<BatchQueue<GccQueueJob>>(
      [self](std::span<GccQueueJob* const> jobs) { self->RunGccBatch(jobs); }, window, options.max_batch_frames);
  runtime->filter_queue_ = std::make_unique<BatchQueue<FilterQueueJob>>(
      [self](std::span<FilterQueueJob* const> jobs) { self->RunFilterBatch(jobs); }, window, options.max_batch_frames);
  return runtime;
}

GpuRuntime::~GpuRuntime() {
  // Stop the dispatchers (they finish queued jobs) before the engines they call go.
  gcc_queue_.reset();
  filter_queue_.reset();
}

void GpuRuntime::AddProducer(Stage stage) {
  if (stage == Stage::kGcc)
    gcc_queue_->AddProducer();
  else
    filter_queue_->AddProducer();
}

void GpuRuntime::RemoveProducer(Stage stage) {
  if (stage == Stage::kGcc)
    gcc_queue_->RemoveProducer();
  else
    filter_queue_->RemoveProducer();
}

void GpuRuntime::RunGcc(GccQueueJob* job) { gcc_queue_->Submit(job); }
void GpuRuntime::StepFilter(FilterQueueJob* job) { filter_queue_->Submit(job); }

void GpuRuntime::RunGccBatch(std::span<GccQueueJob* const> jobs) {
  // Frames batch together only when their transforms match (GccPlan::BatchKey); group them,
  // keeping arrival order within a group.
  std::map<std::string, std::vector<GccQueueJob*>> groups;
  for (GccQueueJob* job : jobs) groups[job->job.plan->key().ToString()].push_back(job);
  std::vector<GccJob> batch;
  for (auto& [key, members] : groups) {
    auto found = gcc_batches_.find(key);
    if (found == gcc_batches_.end()) {
      auto made = GccBatch::Create(members.front()->job.plan->key(), options_.max_batch_frames);
      if (!made.ok()) {
        for (GccQueueJob* job : members) job->status = made.status();
        continue;
      }
      found = gcc_batches_.emplace(key, std::move(made).value()).first;
    }
    batch.clear();
    for (GccQueueJob* job : members) {
      job->status = Status::Ok();
      batch.push_back(job->job);
      batch.back().status = &job->status;  // a bad frame fails its own job only
    }
    const Status status = found->second->Run(batch);
    if (!status.ok()) {  // the device failed: every frame of the group shares the error
      for (GccQueueJob* job : members) job->status = status;
    }
  }
}

void GpuRuntime::RunFilterBatch(std::span<FilterQueueJob* const> jobs) {
  // A session has at most one job in a batch (it waits for it), so the order between its
  // initialisation and others' steps does not matter: initialisations first, in one launch.
  std::vector<FilterQueueJob*> inits, steps;
  for (FilterQueueJob* job : jobs) (job->initialise ? inits : steps).push_back(job);
  if (!inits.empty()) {
    std::vector<ParticleBank::InitRequest> requests;
    std::vector<ParticleBank::InitResult> results(inits.size());
    requests.reserve(inits.size());
    for (FilterQueueJob* job : inits) requests.push_back(job->init);
    const Status status = bank_->Initialise(requests, results);
    for (size_t i = 0; i < inits.size(); ++i) {
      inits[i]->init_result = std::move(results[i]);
      if (!status.ok()) inits[i]->init_result.status = status;
    }
  }
  if (steps.empty()) return;
  std::vector<ParticleBank::StepRequest> requests;
  std::vector<ParticleBank::StepResult> results(steps.size());
  requests.reserve(steps.size());
  for (FilterQueueJob* job : steps) requests.push_back(job->request);
  const Status status = bank_->Step(requests, results);
  for (size_t i = 0; i < steps.size(); ++i) {
    steps[i]->result = std::move(results[i]);
    if (!status.ok()) steps[i]->result.status = status;
  }
}

}  // namespace localizer::gpu
