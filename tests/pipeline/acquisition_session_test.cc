// A session's acquisition, presence and divergence contracts on simulated scenes
// (engine/sim), asserted against the simulator's truth: several exact solutions are all
// kept and honestly reported, a biased pair trips the divergence test whatever the noise
// adaptation did, noise alone is not a source, and a source switched on and off is followed.
#include <gtest/gtest.h>

#include <Eigen/Cholesky>
#include <cmath>
#include <cstdio>
#include <random>

#include "engine/pipeline/mirror_watch.h"
#include "engine/pipeline/scene_campaign.h"
#include "engine/pipeline/session.h"
#include "engine/sim/simulator.h"
#include "tests/pipeline/scenario_run.h"
#include "tests/tdoa/tdoa_test_signals.h"

namespace localizer::engine {
namespace {

struct Run {
  ArrayGeometry array;
  SimResult sim;
  std::vector<Estimate> estimates;
};

AudioSessionConfig ConfigFor(const std::vector<Vec3>& sensors, double c, const SimOptions& sim) {
  AudioSessionConfig config;
  config.sensors_m = sensors;
  config.sound_speed_mps = c;
  config.sample_rate_hz = sim.sample_rate_hz;
  config.band_low_hz = sim.band_low_hz;
  config.band_high_hz = sim.band_high_hz;
  config.seed = 3;
  return config;
}

std::vector<Estimate> Process(const AudioSessionConfig& config, const SimResult& sim) {
  auto session = std::move(*Session::Create(config));
  std::vector<Estimate> out;
  EXPECT_TRUE(session->Process({1, sim.channel_count, sim.samples_per_channel, sim.samples.data()}, &out).ok());
  return out;
}

double PositionNees(const Estimate& e, const Vec3& truth) {
  const Vec3 err = e.state.head<3>() - truth;
  return err.dot(e.covariance.topLeftCorner<3, 3>().ldlt().solve(err));
}

// A regular tetrahedron of 2.8 m edges; the source starts 3 apertures out along a sensor's
// axis, where the other exact TDOA solution lies near the array (7 m away), and moves
// across: the two branches separate and the ghost's path is not a constant velocity.
TEST(AcquisitionSession, KeepsBothSolutionsOfAFourSensorArrayUntilTheDynamicsDecide) {
  const double a = 1.0 / std::sqrt(2.0);
  const std::vector<Vec3> sensors{Vec3(a, a, a), Vec3(a, -a, -a), Vec3(-a, a, -a), Vec3(-a, -a, a)};
  const auto array = *ArrayGeometry::Create(sensors, 1500.0);
  SimOptions o;
  o.duration_s = 20.0;
  o.trajectory.position_m = Vec3(5.0, 5.0, 5.0);
  o.trajectory.velocity_mps = Vec3(0.0, -1.0, 0.0);
  o.snr_db = 10.0;
  o.seed = 4;
  const SimResult sim = *Simulate(array, o);
  const std::vector<Estimate> estimates = Process(ConfigFor(sensors, 1500.0, o), sim);
  ASSERT_FALSE(estimates.empty());
  const Estimate& first = estimates.front();
  ASSERT_TRUE(first.initialised) << "a 10 dB source is acquired at the first frame";
  EXPECT_TRUE(first.source_present);
  EXPECT_GE(first.modes, 2);
  EXPECT_TRUE(first.ambiguous);
  // Whichever mode is reported, the covariance covers the truth (3-D, 4 sigma).
  EXPECT_LT(PositionNees(first, sim.TruthAt(first.t_s).position_m), 16.0);
  // By the last 5 s one hypothesis is left, and it is the truth.
  int late = 0, late_resolved = 0;
  double late_error = 0.0;
  for (const Estimate& e : estimates) {
    if (e.t_s < 15.0 || !e.initialised) continue;
    ++late;
    late_resolved += e.modes == 1 && !e.ambiguous;
    late_error = std::max(late_error, (e.state.head<3>() - sim.TruthAt(e.t_s).position_m).norm());
  }
  EXPECT_GT(late, 20);
  EXPECT_EQ(late_resolved, late);
  EXPECT_LT(late_error, 1.0);
}

// A campaign scene (seed 4000187: 4 hydrophones over 22 m, the source 36 m out, impulses)
// where the far exact solution wins the marginal evidence every frame (white acceleration
// widens the near, true, one's predicted TDOAs) and the filter used to report it 18-35 m off
// with a 1-2 m sd for 5 s. Whatever it reports, it must not be confidently wrong: no more
// than one frame further than 10 CRLBs from the truth with NEES > 50 and not ambiguous.
TEST(AcquisitionSession, AFarSecondSolutionFavouredByTheEvidenceIsNotReportedAsCertain) {
  const SceneRow row = RunRandomScene(4000187, RandomSceneOptions{}, {}, /*keep_frames=*/true);
  ASSERT_TRUE(row.error.empty()) << row.error;
  ASSERT_NE(row.description.find("4 sensors"), std::string::npos) << "the generator changed: " << row.description;
  EXPECT_GT(row.score.initialised_frames, 80);
  EXPECT_LE(row.score.silent_failure_reported_s, 0.13) << row.description;
}

// A campaign scene (seed 1000081: 4 microphones over 1.7 m, a source 1.9-2.6 m away walking
// slowly in a straight line) whose two exact TDOA solutions meet near 8 s: the track leaves
// on the other branch and is 0.6-1.3 m off by the end with every innovation small (before the
// mirror watch: position NEES 90-394, ambiguous 0). The track's mirror then is the truth and
// moves as a source can, so once the watch has seen the mirror move for its window
// (MirrorWatch::kWindowFrames frames after the first frame more than 3 CRLBs off after 9 s)
// every such frame must say ambiguous and cover the truth. Within the window the track's own
// covariance is all there is: with Hann-tapered frames the track leaves gradually (0.3 m at
// 9.6 s to 0.7 m at 10.6 s), and whether one or two of those frames read NEES above 16 moves
// with the last bits of the transforms (issue 20's packed transforms: 22 and 29 at 9.9 and
// 10.1 s, 0.38 and 0.46 m off), so they are not asserted.
// Run with one acceleration std: the default motion (levels, turn rates and speed changes)
// stays on the true branch here, and the contract is the mirror watch's.
TEST(AcquisitionSession, ATrackOnTheOtherBranchSaysTheMirrorIsPossible) {
  const SceneRow row = RunRandomScene(1000081, RandomSceneOptions{}, {}, /*keep_frames=*/true,
                                      [](AudioSessionConfig* c) { c->tracker.particle.SetSingleMotion(); });
  ASSERT_TRUE(row.error.empty()) << row.error;
  ASSERT_NE(row.description.find("4 sensors"), std::string::npos) << "the generator changed: " << row.description;
  int far_off = 0;
  for (const FrameScore& f : row.score.per_frame) {
    if (f.t_s < 9.0 || !f.initialised || !(f.error_m > 3.0 * f.crlb_m)) continue;
    if (++far_off <= MirrorWatch::kWindowFrames) continue;
    EXPECT_TRUE(f.ambiguous) << "t=" << f.t_s << " error " << f.error_m << " m";
    EXPECT_LT(f.nees_position, 16.0) << "t=" << f.t_s << " error " << f.error_m << " m";
  }
  EXPECT_GT(far_off, MirrorWatch::kWindowFrames + 2)
      << "the scene no longer leaves on the other branch: the test needs another scene";
}

// A campaign scene (seed 33000075: 4 microphones over 2.27 m in air, a source walking away
// from 1 to 12 m) whose track takes the far branch at 1.5 s and is 2-7 m off until 8 s with
// small innovations. The mirror of the track's own predicted TDOAs sat 2.5 m from the source
// (the track's range error moves that root by metres near the branch point) and was dropped
// as no longer distinct at 5.3 s: 2 s of a sure position 5.5-7.7 m off. A second watch on
// the frame's measured TDOAs keeps the source as a mirror.
TEST(AcquisitionSession, ATrackMetresOffOnTheOtherBranchKeepsTheSourceAsItsMirror) {
  const SceneRow row = RunRandomScene(33000075, RandomSceneOptions{}, {}, /*keep_frames=*/false);
  ASSERT_TRUE(row.error.empty()) << row.error;
  ASSERT_NE(row.description.find("4 sensors over 2.27 m"), std::string::npos)
      << "the generator changed: " << row.description;
  // 0.68 s since the thirty-second pass (ACCURACY.md): the four frames at 0.85-1.37 s, before
  // the branch, where pair 1's peak is thousands of sigma off; after the branch none.
  EXPECT_LE(row.score.silent_failure_reported_s, 0.7) << row.description;
}

// Two campaign scenes at the service's 4096-sample frames, each a 4-sensor array in water with
// the source beyond one aperture: 9000031 (25 m, the source 41 m out at 0.73 m/s) and 2000138
// (15 m, 35 m out, turning, 3 dB, a surface echo). The particle filter holds both exact
// solutions from the start; its heaviest mode is the wrong one (from 2.6 s, and from the
// start), and then the other mode dies. The mirror watch had followed the heaviest mode's
// mirror all along (and swapped when the heaviest changed), so the truth stays covered. When
// it restarted on the tracker's last mode instead, each scene claimed a sure position
// (sd 0.04 m, 3.4 m) 22 m and 47 m off for 1.0 and 1.5 s. Since: at most 0.37 s (2000138,
// whose figure moves between 0 and 0.37 s with the transforms' last bits), under the 0.5 s
// asserted. The mirror watch is what is tested, so the reference pairs are read as measured:
// with every pair folded into them (pair_fusion.h, the default since) 2000138's track leaves
// the truth at another moment and the figure is 0.74 s (the campaign counts > 1 s).
TEST(AcquisitionSession, WhenTheTrackerDropsAModeTheMirrorItLeftIsStillCovered) {
  for (const uint64_t seed : {9000031u, 2000138u}) {
    const SceneRow row =
        RunRandomScene(seed, RandomSceneOptions{}, {}, /*keep_frames=*/false, [](AudioSessionConfig* c) {
          c->frame_samples = 4096;
          c->hop_samples = 2048;
          c->pair_fusion = false;
        });
    ASSERT_TRUE(row.error.empty()) << row.error;
    ASSERT_NE(row.description.find("4 sensors"), std::string::npos) << "the generator changed: " << row.description;
    EXPECT_GT(row.score.initialised_frames, 50) << seed;
    EXPECT_LE(row.score.silent_failure_s, 0.5) << seed << ": " << row.description;
  }
}

// Campaign scene 3000197 (air, 4 microphones over 0.79 m, the source 0.27 m away at 1 m/s,
// turning; 48 kHz in the campaign's 16384-sample frames): the track runs 10+ CRLBs off while
// sure of itself, and an audit's volume search finds a mode that outscores it. Until the next
// audit, the estimate covers that mode and says ambiguous (Session::Impl::contender): silent
// failure 1.9 s before, 0.9 s with it, under the campaign's 1 s limit. The contender is what is
// tested, so the reference pairs are read as measured: with every pair folded into them
// (pair_fusion.h, the default since) the track errs on other frames and the figure is 1.02 s.
TEST(AcquisitionSession, AModeThatOutscoresTheTrackAtAnAuditIsCoveredUntilTheNext) {
  const SceneRow row = RunRandomScene(3000197, RandomSceneOptions{}, {}, /*keep_frames=*/false,
                                      [](AudioSessionConfig* c) { c->pair_fusion = false; });
  ASSERT_TRUE(row.error.empty()) << row.error;
  ASSERT_NE(row.description.find("4 sensors"), std::string::npos) << "the generator changed: " << row.description;
  EXPECT_GT(row.score.initialised_frames, 20);
  EXPECT_LE(row.score.silent_failure_s, 1.0) << row.description;
}

// A campaign scene (seed 2000127: 4 microphones over 5 m, floor and ceiling echoes) that
// starts with two hypotheses. Multipath association measured each pair at the GCC peak
// nearest the heaviest hypothesis; while the other (the truth) lived, that moved pair 2 onto
// an echo's cross-term 9 ms from the truth's delay, the truth's hypothesis lost every frame and
// the track then sat 3-11 m off for 5 s at NIS ~1. Association now waits until one hypothesis
// is left: under 0.5 s of confident error (was 5.0 s).
TEST(AcquisitionSession, AssociationDoesNotPickPeaksForOneHypothesisWhileOthersLive) {
  const SceneRow row = RunRandomScene(2000127, RandomSceneOptions{}, {}, /*keep_frames=*/true);
  ASSERT_TRUE(row.error.empty()) << row.error;
  ASSERT_NE(row.description.find("4 sensors"), std::string::npos) << "the generator changed: " << row.description;
  EXPECT_GT(row.score.initialised_frames, 80);
  EXPECT_LE(row.score.silent_failure_s, 0.5) << row.description;
}

// A campaign scene (seed 3000179: 4 microphones over 3.1 m in air, tones and broadband at
// 10.6 dB, a source 4.3 m away at 4.6 m/s): two pairs' tallest peaks were weak (SNR ~3, their
// peaks smeared by the source's motion), and association measured each at a smaller peak near
// the track with the precision of the tallest (its SNR). Those peaks held the track on a wrong
// branch at NIS 1-6, 10-30 CRLB off for 1.37 s while claiming a position NEES above 5000 (a
// silent failure: over 1 s). Each such peak now states its own sigma (its height's SNR), the
// track leans on the one strong pair, and the divergence test restarts it sooner.
TEST(AcquisitionSession, APeakPickedNearTheTrackStatesItsOwnPrecision) {
  const SceneRow row = RunRandomScene(3000179, RandomSceneOptions{}, {}, /*keep_frames=*/false);
  ASSERT_TRUE(row.error.empty()) << row.error;
  ASSERT_NE(row.description.find("4 sensors over 3.11 m"), std::string::npos)
      << "the generator changed: " << row.description;
  EXPECT_GT(row.score.initialised_frames, 50);
  EXPECT_LE(row.score.silent_failure_s, 1.0) << row.description;
}

// Campaign scene 15000105 (4 microphones over 2.0 m in air, tones and broadband at 6.4-15.4
// kHz, 9 dB): two of the six pairs hear the source, the other four read noise. Any noise pick
// closes the curve the two leave open, and the first mode stood 7 m along it from the source
// claiming a 0.19 m spread (position NEES 5.9e4; 1.19 s of silent failure). The mode now
// carries points along that curve (acquisition.h, "Open curves"): the track starts along all
// of it, says so (ambiguous), and its spread covers the source until the data decide.
TEST(AcquisitionSession, AFirstModeThatTwoPairsFixStartsAlongTheCurveTheyLeaveOpen) {
  const SceneRow row = RunRandomScene(15000105, RandomSceneOptions{}, {}, /*keep_frames=*/true);
  ASSERT_TRUE(row.error.empty()) << row.error;
  ASSERT_NE(row.description.find("4 sensors over 2.02 m"), std::string::npos)
      << "the generator changed: " << row.description;
  const FrameScore* first = nullptr;
  for (const FrameScore& f : row.score.per_frame) {
    if (f.counted && f.initialised) {
      first = &f;
      break;
    }
  }
  ASSERT_NE(first, nullptr) << "never initialised";
  EXPECT_TRUE(first->ambiguous || first->nees_position < 50.0)
      << "first estimate " << first->error_m << " m off claiming " << first->sd_m << " m (NEES " << first->nees_position
      << ")";
  EXPECT_LE(row.score.silent_failure_s, 0.5) << row.description;
}

// Campaign scene 7000013 (4 microphones over 4.3 m, a broadband source receding at 3 m/s, SNR
// 0.8 dB): the first fix was a 3-pair solve with one wrong peak, and while the track
// converged its cloud spread the predicted delays by 1.5 ms. Those innovations, thousands of
// anchors, fed the noise adaptation, which set every pair's scale to 8 at once; it took ~10 s
// to come down, and meanwhile the track, weighing its pairs 8 times too little, ran 2-5 m
// ahead in range at a 0.3 m sd (2.39 s of silent failure, acquired at 6.1 s). An innovation
// that no admissible noise gives no longer feeds the adaptation (pair_noise.h): 0.68 s,
// acquired at 2.4 s.
TEST(AcquisitionSession, AConvergingTracksInnovationsDoNotInflateTheNoise) {
  const SceneRow row = RunRandomScene(7000013, RandomSceneOptions{}, {}, /*keep_frames=*/false);
  ASSERT_TRUE(row.error.empty()) << row.error;
  ASSERT_NE(row.description.find("4 sensors over 4.29 m"), std::string::npos)
      << "the generator changed: " << row.description;
  EXPECT_LE(row.score.silent_failure_s, 1.0) << row.description;
  EXPECT_LT(row.score.time_to_acquire_s, 4.0) << row.description;
}

// Eight hydrophones (turn-multipath's array, no echo): from 6 s on, channel 3 reaches the
// recorder 4 samples late (a clock slip: ~40 of its pair's sigmas, a persistent bias). The
// divergence test must fire within 12 frames (1.1 s), even though the noise adaptation may
// have scaled that pair's sigma up by 8x meanwhile.
TEST(AcquisitionSession, APersistentlyBiasedPairTripsTheDivergenceTest) {
  const Scenario scenario = *MakeScenario("turn-multipath", 2);
  const auto array = *ArrayGeometry::Create(scenario.sensors_m, scenario.sound_speed_mps);
  SimOptions o = scenario.sim;
  o.surface_reflection_enabled = false;
  o.snr_db = 10.0;
  o.duration_s = 12.0;
  SimResult sim = *Simulate(array, o);
  const int64_t onset = static_cast<int64_t>(6.0 * sim.sample_rate_hz);
  constexpr int kSlip = 4;
  float* channel = sim.samples.data() + 3 * sim.samples_per_channel;
  for (int64_t i = sim.samples_per_channel - 1; i >= onset + kSlip; --i) channel[i] = channel[i - kSlip];
  const std::vector<Estimate> estimates = Process(ConfigFor(scenario.sensors_m, scenario.sound_speed_mps, o), sim);
  int frames_after = 0, fired_at = -1;
  for (const Estimate& e : estimates) {
    if (e.t_s + 0.5 * 4096 / sim.sample_rate_hz <= 6.0) {
      EXPECT_FALSE(e.reinitialised) << "no divergence before the slip, t=" << e.t_s;
      continue;
    }
    ++frames_after;
    if (e.reinitialised && fired_at < 0) fired_at = frames_after;
  }
  ASSERT_GT(frames_after, 20);
  ASSERT_GT(fired_at, 0) << "the divergence test never fired";
  EXPECT_LE(fired_at, 12);
}

// tests/tdoa's tetrahedron in water and a still source 3 apertures out, in frames made by its
// independent signal generator: the whole signal is one block of spec.frame_samples.
struct TetraScene {
  std::vector<Vec3> sensors = testing::TetrahedronSensors();
  ArrayGeometry array = *ArrayGeometry::Create(sensors, 1500.0);
  Vec3 truth = Vec3(5.0, 3.0, -1.0);
  testing::SignalSpec spec;

  // The session's estimates of `samples` (channel-major, spec.frame_samples per channel).
  std::vector<Estimate> Track(const std::vector<float>& samples, int cross_pairs_max_sensors = 8) const {
    AudioSessionConfig config;
    config.sensors_m = sensors;
    config.sound_speed_mps = 1500.0;
    config.sample_rate_hz = spec.sample_rate_hz;
    config.seed = 3;
    config.cross_pairs_max_sensors = cross_pairs_max_sensors;
    auto session = std::move(*Session::Create(config));
    std::vector<Estimate> out;
    EXPECT_TRUE(session->Process({1, 4, spec.frame_samples, samples.data()}, &out).ok());
    return out;
  }
};

// Noise alone for 60 s (11025 Hz, 4096/2048 frames: 322 frames): at a stated per-frame
// false-alarm probability of 1e-3, at least 99 % of frames say no source, none starts a track
// that survives, and the statistic stays below its threshold.
// A 4-sensor array whose channels 0 and 3 share crosstalk louder than the source (a static
// source, 10 dB): pair (0, 3) peaks at lag 0 in every frame, and the three reference pairs
// have an exact solution through that peak. The session's search also measures the pairs
// without the reference (AudioSessionConfig::cross_pairs_max_sensors, 8 by default), which
// outvote it: the first estimate stands at the truth. Without them it stands where the
// crosstalk puts it, with a covariance that excludes the truth, and stays there (6.0 m off
// after 1.5 s); with them, association picks pair (0, 3)'s own peak near the track in every
// later frame, and the track stays 1.6-2.3 m off in range, 2.2 apertures out.
TEST(AcquisitionSession, CrosstalkOnOnePairOfAFourSensorArrayIsOutvotedAtAcquisition) {
  TetraScene scene;
  scene.spec.frame_samples = 16384;  // one block of 1.5 s: seven 4096-sample frames
  const testing::SignalSpec& spec = scene.spec;
  const Vec3& truth = scene.truth;
  std::vector<float> samples = testing::DelayedNoiseFrame(
      spec, testing::ChannelDelaysSamples(scene.array, truth, spec.sample_rate_hz), 10.0, /*seed=*/31);
  const std::vector<float> crosstalk = testing::MultipathFrame(
      spec, {{testing::Path{0.0, 1.0}}, {}, {}, {testing::Path{0.0, 1.0}}}, testing::kNoiseless, /*seed=*/32);
  for (size_t i = 0; i < samples.size(); ++i) samples[i] += 1.5f * crosstalk[i];

  auto first_estimate = [&](int cross_pairs_max_sensors) {
    for (const Estimate& e : scene.Track(samples, cross_pairs_max_sensors)) {
      if (e.initialised) return e;
    }
    return Estimate{};
  };
  const Estimate with = first_estimate(4);
  ASSERT_TRUE(with.initialised);
  const Estimate without = first_estimate(0);
  ASSERT_TRUE(without.initialised);
  const double error_with_m = (with.state.head<3>() - truth).norm();
  const double error_without_m = (without.state.head<3>() - truth).norm();
  std::printf("first estimate %.2f m off (position NEES %.1f) with the cross pairs, %.2f m (NEES %.1f) without\n",
              error_with_m, PositionNees(with, truth), error_without_m, PositionNees(without, truth));
  EXPECT_LT(PositionNees(with, truth), 16.0);
  EXPECT_GT(error_without_m, 3.0);
  EXPECT_GT(PositionNees(without, truth), 100.0);
}

// A still source whose channel 1 hears an echo 1.2 times louder than its direct path, 9
// samples later: every pair with sensor 1 peaks on the echo and the six pairs agree on a
// position 4 m from the source (Acquisition.AChannelWhoseEchoIsLouderKeepsItsEarlierArrivalAsAMode).
// No frame tells the two apart, and the echo scores higher in every one. Acquisition keeps
// sensor 1's earlier arrival, the source, as a mode too, so the first estimate's covariance
// covers the truth; the audits then find the echo's earlier arrival away from the track and
// keep it covered (before: every frame sure of the echo's position; campaign scene 16000131
// claimed 2 mm 1.7 m off for 1.4 s).
TEST(AcquisitionSession, AChannelWhoseEchoIsLouderIsNotReportedAsSureOnTheEcho) {
  TetraScene scene;
  scene.spec.frame_samples = 65536;  // one block of 5.9 s: thirty 4096-sample frames
  const Vec3& truth = scene.truth;
  const std::vector<double> delays = testing::ChannelDelaysSamples(scene.array, truth, scene.spec.sample_rate_hz);
  std::vector<std::vector<testing::Path>> channels;
  for (size_t c = 0; c < 4; ++c) channels.push_back({{delays[c] + 40.0, 1.0}});
  channels[1].push_back({delays[1] + 49.0, 1.2});
  const std::vector<Estimate> out = scene.Track(testing::MultipathFrame(scene.spec, channels, 10.0, /*seed=*/41));
  int initialised = 0, sure_and_wrong = 0;
  for (const Estimate& e : out) {
    if (!e.initialised) continue;
    const double nees = PositionNees(e, truth);
    if (++initialised == 1) {
      EXPECT_LT(nees, 16.0) << "the first estimate must cover the source";
    }
    sure_and_wrong += !e.ambiguous && nees > 16.0;
  }
  std::printf("%d estimates, %d sure and wrong (position NEES > 16, not ambiguous)\n", initialised, sure_and_wrong);
  EXPECT_GE(initialised, 25);
  // The start's earlier-arrival label may lose to the echo before the first audit; from that
  // audit on the echo's other side is covered.
  EXPECT_LE(sure_and_wrong, 8);
}

TEST(AcquisitionSession, SixtySecondsOfNoiseHoldNoSource) {
  const Scenario scenario = *MakeScenario("tetra-water", 1);
  AudioSessionConfig config = SessionConfigFor(scenario);
  config.band_low_hz = config.band_high_hz = 0.0;  // a user without a band hint
  SimResult noise;
  noise.channel_count = 4;
  noise.sample_rate_hz = config.sample_rate_hz;
  noise.samples_per_channel = static_cast<int64_t>(60.0 * noise.sample_rate_hz);
  noise.samples.resize(static_cast<size_t>(noise.channel_count * noise.samples_per_channel));
  std::mt19937_64 rng(8);
  std::normal_distribution<float> gauss(0.0f, 0.1f);
  for (float& v : noise.samples) v = gauss(rng);
  const std::vector<Estimate> estimates = Process(config, noise);
  ASSERT_GT(estimates.size(), 300u);
  int present = 0, initialised = 0;
  for (const Estimate& e : estimates) {
    present += e.source_present;
    initialised += e.initialised;
    EXPECT_GT(e.presence_threshold, 0.0);
  }
  EXPECT_LE(present, static_cast<int>(estimates.size()) / 100);
  EXPECT_LE(initialised, static_cast<int>(estimates.size()) / 100);
}

// tetra-water's source on for 0-5 s and 11-20 s, silent (noise only) for 5-11 s: presence
// follows each switch at the first frame wholly on the other side, the silent track is
// dropped after source_timeout_s (2 s), and the source is re-acquired at its first frame back
// (then tracked within 1 m for 4 s, while it is 6-9 m from the 2 m array; further out the
// range of a 4-sensor array is barely observable and the track's error grows with its sd).
TEST(AcquisitionSession, ASourceSwitchedOffAndOnIsFlaggedDroppedAndReacquired) {
  const Scenario scenario = *MakeScenario("tetra-water", 3);
  const auto array = *ArrayGeometry::Create(scenario.sensors_m, scenario.sound_speed_mps);
  SimOptions o = scenario.sim;
  o.duration_s = 20.0;
  o.snr_db = kNoNoiseSnrDb;
  SimResult sim = *Simulate(array, o);
  // Silence the source between 8 and 16 s, then add noise 15 dB below its mean power.
  const double fs = sim.sample_rate_hz;
  double power = 0.0;
  for (float v : sim.samples) power += static_cast<double>(v) * v;
  power /= static_cast<double>(sim.samples.size());
  std::mt19937_64 rng(12);
  std::normal_distribution<double> gauss(0.0, std::sqrt(power) * std::pow(10.0, -15.0 / 20.0));
  for (int c = 0; c < sim.channel_count; ++c) {
    for (int64_t i = 0; i < sim.samples_per_channel; ++i) {
      float& v = sim.samples[static_cast<size_t>(c * sim.samples_per_channel + i)];
      const double t = static_cast<double>(i) / fs;
      if (t >= 5.0 && t < 11.0) v = 0.0f;
      v += static_cast<float>(gauss(rng));
    }
  }
  AudioSessionConfig config = SessionConfigFor(scenario);
  const std::vector<Estimate> estimates = Process(config, sim);
  const double half_frame_s = 0.5 * config.frame_samples / fs;
  int first_present_after_on = -1, first_absent_after_off = -1, frames_after_on = 0, frames_after_off = 0;
  bool dropped = false;
  double error_after_reacquire = 0.0;
  for (const Estimate& e : estimates) {
    const double start = e.t_s - half_frame_s, end = e.t_s + half_frame_s;
    if (end <= 5.0) {
      EXPECT_TRUE(e.source_present) << "t=" << e.t_s;
    } else if (start >= 5.0 && end <= 11.0) {
      ++frames_after_off;
      if (!e.source_present && first_absent_after_off < 0) first_absent_after_off = frames_after_off;
      if (e.t_s > 5.0 + 2.0 + 2 * half_frame_s) dropped |= !e.initialised;
    } else if (start >= 11.0 && e.t_s < 15.0) {
      ++frames_after_on;
      if (e.source_present && first_present_after_on < 0) first_present_after_on = frames_after_on;
      if (frames_after_on >= 3 && e.initialised) {
        error_after_reacquire =
            std::max(error_after_reacquire, (e.state.head<3>() - sim.TruthAt(e.t_s).position_m).norm());
      }
    }
  }
  EXPECT_EQ(first_absent_after_off, 1);
  EXPECT_TRUE(dropped) << "the silent track is dropped after source_timeout_s";
  EXPECT_EQ(first_present_after_on, 1);
  EXPECT_LT(error_after_reacquire, 1.0);
}

// The multipath scene (8 hydrophones, surface echo -0.9, 5 dB) starts its track at the first
// frame, with a covariance that covers the truth, where the former single fix waited for
// frames whose every pair was clean (and never found one on harder scenes).
TEST(AcquisitionSession, MultipathSceneInitialisesAtTheFirstFrame) {
  const ScenarioRun run = TrackScenario("turn-multipath", 1, Likelihood::kPeak);
  ASSERT_FALSE(run.estimates.empty());
  const Estimate& first = run.estimates.front();
  ASSERT_TRUE(first.initialised);
  EXPECT_LT(PositionNees(first, run.sim.TruthAt(first.t_s).position_m), 16.0);
}

}  // namespace
}  // namespace localizer::engine
