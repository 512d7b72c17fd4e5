#include "gpu/backend/gpu_particle_filter.h"

#include <string>

#include "engine/models/constant_velocity.h"

namespace localizer::gpu {

StatusOr<std::unique_ptr<GpuParticleFilter>> GpuParticleFilter::Create(std::shared_ptr<GpuRuntime> runtime,
                                                                       const engine::ArrayGeometry& array,
                                                                       const engine::ParticleFilterOptions& options) {
  LOCALIZER_RETURN_IF_ERROR(options.Validate());
  if (options.likelihood == engine::Likelihood::kMixture) {
    // BuildComponents keeps such filters on the CPU; the device kernels weigh by peak or GCC.
    return InvalidArgument("the GPU particle filter has no mixture likelihood (use the CPU filter)");
  }
  if (!options.single_motion()) {
    return InvalidArgument(
        "the GPU particle filter has one acceleration std, no turn rates and no speed changes (set "
        "accel_level_floor = accel_level_ceiling = 1, turn_rate_max_radps = 0 and speed_change_max_mps2 = 0, or "
        "use the CPU filter)");
  }
  auto slot = runtime->bank().Open(array, options);
  if (!slot.ok()) return slot.status();
  return std::unique_ptr<GpuParticleFilter>(
      new GpuParticleFilter(std::move(runtime), *slot, array.pair_count(), options));
}

GpuParticleFilter::GpuParticleFilter(std::shared_ptr<GpuRuntime> runtime, int slot, int pairs,
                                     const engine::ParticleFilterOptions& options)
    : runtime_(std::move(runtime)), slot_(slot), pairs_(pairs), options_(options), noise_(options.tdoa_sigma_s) {}

GpuParticleFilter::~GpuParticleFilter() {
  Suspend();
  runtime_->bank().Close(slot_);
}

void GpuParticleFilter::Suspend() {
  if (producing_) runtime_->RemoveProducer(GpuRuntime::Stage::kFilter);
  producing_ = false;
}

Status GpuParticleFilter::RunInitialisation(const ParticleBank::InitRequest& request) {
  FilterQueueJob job;
  job.initialise = true;
  job.init = request;
  job.init.slot = slot_;
  if (!producing_) runtime_->AddProducer(GpuRuntime::Stage::kFilter);  // from this job on
  producing_ = true;
  runtime_->StepFilter(&job);
  if (!job.init_result.status.ok()) {
    Suspend();  // a filter that did not start submits nothing until it is initialised again
    return job.init_result.status;
  }
  state_ = job.init_result.state;
  pending_dt_s_ = 0.0;
  initialised_ = true;
  ess_ = options_.particles;
  return Status::Ok();
}

Status GpuParticleFilter::Initialise(const engine::TrackState& belief) {
  const auto root = engine::BeliefRoot(belief);
  if (!root.ok()) return root.status();
  ParticleBank::InitRequest request;
  request.mean = belief.mean;
  request.root = *root;
  return RunInitialisation(request);
}

Status GpuParticleFilter::InitialiseRegion(const engine::Vec3& min_m, const engine::Vec3& max_m,
                                           double speed_sigma_mps) {
  LOCALIZER_RETURN_IF_ERROR(engine::ValidateRegion(min_m, max_m, speed_sigma_mps));
  ParticleBank::InitRequest request;
  request.region = true;
  request.min_m = min_m;
  request.max_m = max_m;
  request.speed_sigma_mps = speed_sigma_mps;
  return RunInitialisation(request);
}

void GpuParticleFilter::Predict(double dt_s) {
  if (initialised_ && dt_s > 0.0) pending_dt_s_ += dt_s;
}

Status GpuParticleFilter::Step(const engine::Measurement* measurement, ParticleBank::StepResult* result) {
  FilterQueueJob job;
  job.request.slot = slot_;
  job.request.dt_s = pending_dt_s_;
  job.request.measurement = measurement;
  job.request.used = noise_.used().data();
  job.request.sigmas_s = noise_.sigmas_s().data();
  runtime_->StepFilter(&job);
  if (!job.result.status.ok()) return job.result.status;
  pending_dt_s_ = 0.0;
  state_ = job.result.state;
  *result = std::move(job.result);
  return Status::Ok();
}

StatusOr<engine::UpdateReport> GpuParticleFilter::Update(const engine::Measurement& m) {
  if (!initialised_) return FailedPrecondition("particle filter updated before initialisation");
  if (static_cast<int>(m.pairs.size()) != pairs_) {
    return InvalidArgument("measurement has " + std::to_string(m.pairs.size()) + " pairs; the array has " +
                           std::to_string(pairs_));
  }
  if (!(m.sample_rate_hz > 0.0)) return InvalidArgument("measurement sample_rate_hz must be > 0");
  engine::UpdateReport report;
  report.pair_count = noise_.Select(m, options_.min_peak_snr);
  ParticleBank::StepResult result;
  LOCALIZER_RETURN_IF_ERROR(Step(report.pair_count > 0 ? &m : nullptr, &result));
  if (report.pair_count == 0) {  // predicted only: nothing to condition on
    report.ess = ess_;
    report.tdoa_sigma_s = noise_.rms_sigma_s();
    return report;
  }
  noise_.Finish(result.innovations, m.sample_rate_hz, &report);
  ess_ = result.ess;
  report.ess = ess_;
  return report;
}

engine::TrackState GpuParticleFilter::State() const {
  if (!initialised_ || !(pending_dt_s_ > 0.0)) return state_;
  // The prediction's moments on the host: the device applies it with the next step. A
  // device round for them alone would double each frame's trips through the dispatcher.
  // Exact under the model, so the cloud's moments once the device predicts it (in expectation).
  const engine::ConstantVelocity model{options_.accel_noise_mps2};
  const engine::Mat6 f = model.Transition(pending_dt_s_);
  engine::TrackState predicted;
  predicted.mean = f * state_.mean;
  predicted.covariance = f * state_.covariance * f.transpose() + model.ProcessNoise(pending_dt_s_);
  return predicted;
}

}  // namespace localizer::gpu
