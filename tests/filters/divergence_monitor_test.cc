// The divergence test's contract (engine/filters/divergence_monitor.h): silent on a
// consistent filter, quick on a lost one, and not fooled by isolated outliers.
#include "engine/filters/divergence_monitor.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

namespace localizer::engine {
namespace {

constexpr double kCap = 6.0;  // the caller's cap on |z| (pair_noise.cc)

double Capped(double z) { return std::max(-kCap, std::min(kCap, z)); }

// Feeds `frames` updates of `pairs` standard normal innovations (capped as the caller caps
// them); returns how many times the monitor fired.
int Alarms(DivergenceMonitor* monitor, std::mt19937_64* rng, int frames, int pairs) {
  std::normal_distribution<double> normal;
  int alarms = 0;
  for (int f = 0; f < frames; ++f) {
    std::vector<double> z(static_cast<size_t>(pairs));
    double nis = 0.0;
    for (double& v : z) {
      v = Capped(normal(*rng));
      nis += v * v;
    }
    alarms += monitor->Add(nis, pairs, z);
  }
  return alarms;
}

TEST(DivergenceMonitor, AConsistentFilterRaisesAlmostNoAlarms) {
  std::mt19937_64 rng(15);
  for (int pairs : {3, 6, 28}) {
    DivergenceMonitor monitor;
    const int frames = 20000;
    // The per-frame rate the session can live with: one false restart per 1000 frames
    // (about a minute at 44.1 kHz / 2048 hop) would be costly; the bound is 1e-3 with margin.
    EXPECT_LE(Alarms(&monitor, &rng, frames, pairs), frames / 1000) << pairs << " pairs";
  }
}

TEST(DivergenceMonitor, ThreeFramesOfGrossInnovationsTripTheWholesaleTestBeforeTheWindowFills) {
  DivergenceMonitor monitor(8);
  // Every pair at the cap: 3 frames x 3 pairs x 36 = 324 against 4 x chi2(0.999, 9) = 111.
  const std::vector<double> z = {kCap, -kCap, kCap};
  EXPECT_FALSE(monitor.Add(108.0, 3, z));
  EXPECT_FALSE(monitor.Add(108.0, 3, {-kCap, kCap, -kCap}));
  EXPECT_TRUE(monitor.Add(108.0, 3, z));
}

TEST(DivergenceMonitor, ARunOfExtremeSameSignInnovationsOnOnePairTripsWithinThreeFrames) {
  DivergenceMonitor monitor(8);
  // One pair the track cannot explain; the others fine and the frame's NIS modest.
  const std::vector<double> z = {0.3, kCap, -0.5};
  EXPECT_FALSE(monitor.Add(36.3, 3, z));
  EXPECT_FALSE(monitor.Add(36.3, 3, z));
  EXPECT_TRUE(monitor.Add(36.3, 3, z));
}

TEST(DivergenceMonitor, IsolatedOrSignAlternatingOutliersDoNotTripIt) {
  DivergenceMonitor monitor(8);
  // An echo that wins one pair every other frame, on alternate sides: not a lost track.
  for (int f = 0; f < 64; ++f) {
    const double z0 = f % 2 == 1 ? 0.4 : (f % 4 == 0 ? kCap : -kCap);
    EXPECT_FALSE(monitor.Add(z0 * z0 + 0.98, 3, {z0, 0.7, -0.7})) << "frame " << f;
  }
  // Or one frame in three on the same side.
  for (int f = 0; f < 64; ++f) {
    const double z0 = (f % 3 == 0) ? kCap : 0.4;
    EXPECT_FALSE(monitor.Add(z0 * z0 + 0.5, 3, {z0, -0.5, 0.5})) << "frame " << f;
  }
}

TEST(DivergenceMonitor, APersistentModerateBiasTripsTheWindowedTestOnlyOnceTheWindowIsFull) {
  DivergenceMonitor monitor(8);
  // Mean z of 3.5 on one pair: beyond 3 x, but below the run test's extreme.
  const std::vector<double> z = {3.5, 0.2, -0.2};
  for (int f = 0; f < 7; ++f) EXPECT_FALSE(monitor.Add(12.33, 3, z)) << "frame " << f;
  EXPECT_TRUE(monitor.Add(12.33, 3, z));
}

TEST(DivergenceMonitor, ResetForgetsThePast) {
  DivergenceMonitor monitor(8);
  const std::vector<double> z = {0.3, kCap, -0.5};
  monitor.Add(36.3, 3, z);
  monitor.Add(36.3, 3, z);
  monitor.Reset();
  EXPECT_FALSE(monitor.Add(36.3, 3, z));
  EXPECT_GT(monitor.ratio(), 0.0);
}

}  // namespace
}  // namespace localizer::engine
