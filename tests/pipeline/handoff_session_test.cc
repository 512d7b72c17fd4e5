// The GPU backend's particle filter holds one hypothesis and no bounds, so a session on it
// acquires with the CPU filter and hands the track over once one hypothesis is left
// (engine/filters/handoff_tracker.h). Shown here without a GPU: a stand-in provider gives the
// CPU GCC and, as its "device" filter, a CPU particle filter seen only through the base
// Tracker interface (one hypothesis, heaviest-mode mixture start, bounds ignored), as the
// device filter is.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <memory>

#include "engine/filters/handoff_tracker.h"
#include "engine/pipeline/backend.h"
#include "tests/pipeline/scenario_run.h"

namespace localizer::engine {
namespace {

// Counts the updates it was given; everything else the base Tracker's defaults.
class OneHypothesisFilter final : public Tracker {
 public:
  OneHypothesisFilter(std::unique_ptr<Tracker> inner, int* updates) : inner_(std::move(inner)), updates_(updates) {}
  bool initialised() const override { return inner_->initialised(); }
  Status Initialise(const TrackState& belief) override { return inner_->Initialise(belief); }
  void Predict(double dt_s) override { inner_->Predict(dt_s); }
  StatusOr<UpdateReport> Update(const Measurement& m) override {
    ++*updates_;
    return inner_->Update(m);
  }
  TrackState State() const override { return inner_->State(); }

 private:
  std::unique_ptr<Tracker> inner_;
  int* updates_;
};

class StandInProvider final : public BackendProvider {
 public:
  std::string UnavailableReason() const override { return ""; }
  StatusOr<std::unique_ptr<TdoaEstimator>> MakeEstimator(const ArrayGeometry& array,
                                                         const GccOptions& options) override {
    auto made = GccPhatEstimator::Create(array, options);
    if (!made.ok()) return made.status();
    return std::unique_ptr<TdoaEstimator>(std::move(made).value());
  }
  StatusOr<std::unique_ptr<Tracker>> MakeTracker(const ArrayGeometry& array,
                                                 const ParticleFilterOptions& options) override {
    auto made = ParticleFilter::Create(array, options);
    if (!made.ok()) return made.status();
    return std::unique_ptr<Tracker>(std::make_unique<OneHypothesisFilter>(std::move(made).value(), &device_updates));
  }
  int device_updates = 0;
};

void OneAccelerationStd(AudioSessionConfig* config) { config->tracker.particle.SetSingleMotion(); }

// tetra-air (0.4 m tetrahedron, the source at 2-3 m: two exact TDOA solutions at the start).
// Started from the heaviest mode alone, as the device filter was before the hand-off, the
// pooled RMSE over these seeds was 19x the CPU filter's (2.14 m against 0.11 m: checked; the
// GPU backend measured 2.2 m against 0.12 m over 10 seeds on an H200). Handed on, it must
// stay within 25 % of the CPU's, and the follower must take most of the updates.
TEST(HandoffSession, AOneHypothesisFilterFollowsWhatTheCpuFilterAcquired) {
  auto provider = std::make_shared<StandInProvider>();
  const auto previous = SetGpuProvider(provider);
  double cpu_sq = 0.0, handed_sq = 0.0;
  int frames = 0;
  constexpr int kSeeds = 6;
  for (int seed = 1; seed <= kSeeds; ++seed) {
    const auto cpu = TrackScenario("tetra-air", seed, Likelihood::kPeak, BackendChoice::kCpu, FilterKind::kPf,
                                   MotionModelKind::kCv, OneAccelerationStd);
    const auto handed = TrackScenario("tetra-air", seed, Likelihood::kPeak, BackendChoice::kGpu, FilterKind::kPf,
                                      MotionModelKind::kCv, OneAccelerationStd);
    ASSERT_EQ(handed.estimates.size(), cpu.estimates.size());
    cpu_sq += cpu.score.rmse_m * cpu.score.rmse_m;
    handed_sq += handed.score.rmse_m * handed.score.rmse_m;
    frames += static_cast<int>(cpu.estimates.size());
  }
  SetGpuProvider(previous);
  const double cpu_rmse = std::sqrt(cpu_sq / kSeeds), handed_rmse = std::sqrt(handed_sq / kSeeds);
  std::printf("tetra-air peak, pooled over %d seeds: cpu %.4f m, handed on %.4f m; follower updates %d of %d frames\n",
              kSeeds, cpu_rmse, handed_rmse, provider->device_updates, frames);
  EXPECT_LE(handed_rmse, 1.25 * cpu_rmse);
  EXPECT_GT(provider->device_updates, frames / 2);
}

}  // namespace
}  // namespace localizer::engine
