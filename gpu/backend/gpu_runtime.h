// The process's GPU state behind the provider: the particle bank, one GccBatch engine per
// frame shape, and the two dispatchers (BatchQueue) that turn many sessions' calls into one
// launch sequence each. Created on the first GPU session; shared by all of them.
// Internal to gpu/backend.
#pragma once

#include <memory>
#include <mutex>
#include <string>
#include <unordered_map>

#include "gpu/backend/gpu_backend.h"
#include "gpu/batch/batch_queue.h"
#include "gpu/filters/particle_bank.h"
#include "gpu/tdoa/gcc_batch.h"

namespace localizer::gpu {

// One session's frame on its way through the GCC dispatcher.
struct GccQueueJob {
  GccJob job;
  Status status;
};

// One session's filter step, or its (re)initialisation, on its way through the
// particle-filter dispatcher: the initialisations of a batch run as one launch
// (ParticleBank::Initialise) before its steps run as another.
struct FilterQueueJob {
  bool initialise = false;  // true: `init` and `init_result`; false: `request` and `result`
  ParticleBank::StepRequest request;
  ParticleBank::StepResult result;
  ParticleBank::InitRequest init;
  ParticleBank::InitResult init_result;
};

class GpuRuntime {
 public:
  // FAILED_PRECONDITION without a device; RESOURCE_EXHAUSTED/INTERNAL from the device.
  static StatusOr<std::shared_ptr<GpuRuntime>> Create(const GpuBackendOptions& options);
  ~GpuRuntime();

  // Blocks until the job's batch ran; the job's status says how it went.
  void RunGcc(GccQueueJob* job);
  void StepFilter(FilterQueueJob* job);

  // A session's estimator or filter joins / leaves a dispatcher's producers
  // (batch_queue.h): when every one of them waits, the batch runs without the window.
  enum class Stage { kGcc, kFilter };
  void AddProducer(Stage stage);
  void RemoveProducer(Stage stage);

  ParticleBank& bank() { return *bank_; }
  BatchQueueStats gcc_stats() const { return gcc_queue_->stats(); }
  BatchQueueStats filter_stats() const { return filter_queue_->stats(); }

 private:
  explicit GpuRuntime(const GpuBackendOptions& options) : options_(options) {}
  void RunGccBatch(std::span<GccQueueJob* const> jobs);
  void RunFilterBatch(std::span<FilterQueueJob* const> jobs);

  GpuBackendOptions options_;
  std::unique_ptr<ParticleBank> bank_;
  // One engine per batch key, made on first use; touched only by the GCC dispatcher thread.
  std::unordered_map<std::string, std::unique_ptr<GccBatch>> gcc_batches_;
  // Declared last: destroyed first, so their threads stop before what they use goes.
  std::unique_ptr<BatchQueue<FilterQueueJob>> filter_queue_;
  std::unique_ptr<BatchQueue<GccQueueJob>> gcc_queue_;
};

}  // namespace localizer::gpu
