// engine::Tracker on the GPU: the CPU particle filter's algorithm (particle_filter.h) with
// its particles resident in the shared device bank between frames (one slot per session).
// Predict only records the time step; Update sends the step (predict, likelihood, weights,
// resampling) through the shared filter dispatcher, so many sessions' updates run as one
// launch sequence; Initialise and InitialiseRegion go through the same dispatcher, so
// sessions that start or restart together initialise in one launch. State() returns the
// weighted moments the last step (or initialisation) brought back; after a Predict not yet
// followed by an Update, those moments carried forward on the host (F P F^T + Q of the
// constant-velocity model, exact in expectation), so that reading the prediction costs no
// trip to the device. Pair selection, the adaptive TDOA noise and the
// NIS are the CPU filter's (engine/filters/pair_noise.h).
// Internal to gpu/backend.
#pragma once

#include <memory>

#include "engine/array/array_geometry.h"
#include "engine/filters/pair_noise.h"
#include "engine/filters/particle_filter.h"
#include "gpu/backend/gpu_runtime.h"

namespace localizer::gpu {

class GpuParticleFilter final : public engine::Tracker {
 public:
  // INVALID_ARGUMENT as ParticleFilter::Create; RESOURCE_EXHAUSTED when the bank is full.
  static StatusOr<std::unique_ptr<GpuParticleFilter>> Create(std::shared_ptr<GpuRuntime> runtime,
                                                             const engine::ArrayGeometry& array,
                                                             const engine::ParticleFilterOptions& options);
  ~GpuParticleFilter() override;  // frees the slot

  bool initialised() const override { return initialised_; }
  Status Initialise(const engine::TrackState& belief) override;
  Status InitialiseRegion(const engine::Vec3& min_m, const engine::Vec3& max_m, double speed_sigma_mps) override;
  void Predict(double dt_s) override;
  StatusOr<engine::UpdateReport> Update(const engine::Measurement& measurement) override;
  engine::TrackState State() const override;
  // Leaves the filter dispatcher's producers until the next initialisation.
  void Suspend() override;

 private:
  GpuParticleFilter(std::shared_ptr<GpuRuntime> runtime, int slot, int pairs, const engine::ParticleFilterOptions& o);
  // Runs one step through the dispatcher (measurement nullptr: predict only).
  Status Step(const engine::Measurement* measurement, ParticleBank::StepResult* result);
  // Initialises the slot through the filter dispatcher, so that sessions starting together
  // share one launch (ParticleBank::Initialise), and keeps the moments it brings back.
  Status RunInitialisation(const ParticleBank::InitRequest& request);

  std::shared_ptr<GpuRuntime> runtime_;
  int slot_;
  int pairs_;
  engine::ParticleFilterOptions options_;
  engine::PairNoise noise_;
  bool initialised_ = false;
  // A registered producer of the filter dispatcher: from the first initialisation until
  // Suspend. Not before: a session still acquiring on the CPU (engine/filters/
  // handoff_tracker.h) submits nothing, and the dispatcher would wait out its window for it.
  bool producing_ = false;
  double ess_ = 0.0;
  double pending_dt_s_ = 0.0;  // predicted, not yet sent to the device
  engine::TrackState state_;
};

}  // namespace localizer::gpu
