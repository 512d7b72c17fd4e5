// A tracker that acquires with one filter and follows with another: a (re)start from several
// hypotheses (a mixture of modes, or a region) goes to `acquire` (a filter that keeps them
// all: the CPU particle filter, with its labelled modes, contenders and bounds), and once it
// has held one hypothesis for kSteadyUpdates updates in a row the track is handed to
// `follow` (initialised from acquire's state: one Gaussian, which a single hypothesis is
// close to), which then predicts and updates alone until the next restart. A start from one
// Gaussian goes to `follow` at once. Used where `follow` is cheaper but cannot hold several
// hypotheses (the GPU particle filter: one slot of the shared device bank, no labels and no
// bounds), so that acquisition keeps every solution the data allows whichever filter runs
// the steady state.
#pragma once

#include <memory>
#include <vector>

#include "engine/filters/tracker.h"

namespace localizer::engine {

class HandoffTracker final : public Tracker {
 public:
  // Consecutive updates with one hypothesis before the hand-off.
  static constexpr int kSteadyUpdates = 3;

  HandoffTracker(std::unique_ptr<Tracker> acquire, std::unique_ptr<Tracker> follow)
      : acquire_(std::move(acquire)), follow_(std::move(follow)) {}

  bool initialised() const override { return active().initialised(); }
  Status Initialise(const TrackState& belief) override;
  Status InitialiseRegion(const Vec3& min_m, const Vec3& max_m, double speed_sigma_mps) override;
  Status InitialiseMixture(const std::vector<WeightedBelief>& components) override;
  std::vector<WeightedBelief> Hypotheses() const override { return active().Hypotheses(); }
  // Both filters get the bounds (a follower that ignores them, as the GPU filter does, holds
  // the track only while acquire has put it inside them).
  void SetBounds(const Vec3& min_m, const Vec3& max_m) override;
  void Predict(double dt_s) override { active().Predict(dt_s); }
  StatusOr<UpdateReport> Update(const Measurement& measurement) override;
  TrackState State() const override { return active().State(); }
  Status SetArray(const ArrayGeometry& array) override { return active().SetArray(array); }
  std::vector<ModelProbability> ModelProbabilities() const override { return active().ModelProbabilities(); }

  // Which filter holds the track now: true once handed to `follow`.
  bool following() const { return following_; }

 private:
  Tracker& active() const { return following_ ? *follow_ : *acquire_; }
  void Restarted();  // back to acquire after a (re)start; the follower is suspended

  std::unique_ptr<Tracker> acquire_;
  std::unique_ptr<Tracker> follow_;
  bool following_ = false;
  int single_updates_ = 0;  // acquire's consecutive updates with one hypothesis
};

}  // namespace localizer::engine
