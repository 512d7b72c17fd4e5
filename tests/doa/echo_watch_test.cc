// The echo test and watch (engine/doa/echo_test.h, echo_watch.h): a delayed copy of a source
// from another direction correlates with it at its delay, on the side where it lags; two
// independent sources do not; the watch calls the weaker, lagging, never-alone track an echo
// and nothing else. Scenes: far-field plane waves with exact delays (tests/doa/plane_wave.h);
// a reflection is a source that repeats another's signal, scaled and delayed.
#include "engine/doa/echo_watch.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <vector>

#include "engine/doa/array_shape.h"
#include "engine/doa/echo_test.h"
#include "tests/doa/plane_wave.h"

namespace localizer::engine {
namespace {

using testing::PlaneSource;
using testing::PlaneWaveFrame;
using testing::PlaneWaveScene;

constexpr double kDegree = std::numbers::pi / 180.0;
constexpr double kDelaySamples = 30.0;  // the reflection's extra path: 0.64 m at 16 kHz in air

// 8 microphones 4 cm apart along x (28 cm): it resolves cone angles 35 degrees apart above ~2 kHz.
std::vector<Vec3> Line() {
  std::vector<Vec3> s;
  for (int i = 0; i < 8; ++i) s.emplace_back(0.04 * i, 0, 0);
  return s;
}
Vec3 AtCone(double degrees) { return {std::cos(degrees * kDegree), std::sin(degrees * kDegree), 0.0}; }

// The scenes delay the copy by kDelaySamples at the origin (sensor 0); beams are steered about
// the array's centroid (0.14 m along x), where the copy from 75 degrees lags the source from 40
// by that plus the plane waves' travel from the centroid to the origin: 3.3 samples more.
double CentroidLag() {
  const Vec3 centroid(0.14, 0.0, 0.0);
  return kDelaySamples + centroid.dot(AtCone(40.0) - AtCone(75.0)) / 343.0 * 16000.0;
}

PlaneWaveScene SceneOn(std::vector<Vec3> sensors) {
  PlaneWaveScene scene;
  scene.sensors_m = std::move(sensors);
  scene.noise_power = 0.01;
  return scene;
}

EchoTestOptions TestOptions() {
  EchoTestOptions o;
  o.band_low_hz = 100.0;
  o.band_high_hz = 7000.0;
  return o;
}

// A source at 40 degrees and, from 75 degrees, its reflection (gain, delay) or an independent source.
std::vector<PlaneSource> Sources(bool echo, double gain = 0.7) {
  PlaneSource direct{AtCone(40.0), 1.0};
  PlaneSource other{AtCone(75.0), gain * gain};
  if (echo) other.echo_of = 0, other.gain = gain, other.delay_samples = kDelaySamples;
  return {direct, other};
}

int ArgMax(const std::vector<double>& v) {
  return static_cast<int>(std::max_element(v.begin(), v.end()) - v.begin()) + 1;  // lags start at 1
}
double MaxAbs(const std::vector<double>& v) {
  double m = 0.0;
  for (double x : v) m = std::max(m, std::abs(x));
  return m;
}

TEST(EchoTest, AReflectionCorrelatesWithItsSourceAtItsDelayWhereItLags) {
  const PlaneWaveScene scene = SceneOn(Line());
  auto test = EchoTest::Create(scene.sensors_m, TestOptions());
  ASSERT_TRUE(test.ok()) << test.status().ToString();
  EXPECT_EQ(test->max_lag(), 192);  // 12 ms
  for (uint64_t seed = 1; seed <= 5; ++seed) {
    const std::vector<float> frame = PlaneWaveFrame(scene, Sources(/*echo=*/true), seed);
    test->Load(frame.data());
    EchoEvidence e;
    ASSERT_TRUE(test->Compare(AtCone(40.0), AtCone(75.0), &e));
    EXPECT_NEAR(ArgMax(e.lagging), CentroidLag(), 1.0) << seed;
    // Beam 75 holds 0.7 x the source (its own direction's) and what it leaks of the direct
    // sound; one frame of 512 samples holds the copy over 482 of them.
    EXPECT_GT(*std::max_element(e.lagging.begin(), e.lagging.end()), 0.4) << seed;
    EXPECT_LT(MaxAbs(e.leading), 0.25) << seed;
    EXPECT_LT(e.power_j, e.power_i) << seed;
    // The other way round, the same correlation is on the leading side.
    EchoEvidence reverse;
    ASSERT_TRUE(test->Compare(AtCone(75.0), AtCone(40.0), &reverse));
    EXPECT_NEAR(ArgMax(reverse.leading), CentroidLag(), 1.0) << seed;
  }
}

TEST(EchoTest, IndependentSourcesDoNotCorrelateAtAnyLag) {
  const PlaneWaveScene scene = SceneOn(Line());
  auto test = EchoTest::Create(scene.sensors_m, TestOptions());
  ASSERT_TRUE(test.ok());
  double largest = 0.0;
  for (uint64_t seed = 1; seed <= 5; ++seed) {
    const std::vector<float> frame = PlaneWaveFrame(scene, Sources(/*echo=*/false, 1.0), seed);
    test->Load(frame.data());
    EchoEvidence e;
    ASSERT_TRUE(test->Compare(AtCone(40.0), AtCone(75.0), &e));
    largest = std::max({largest, MaxAbs(e.lagging), MaxAbs(e.leading)});
  }
  // Chance alone over ~190 lags either side of a frame: under about 0.2.
  EXPECT_LT(largest, 0.25);
}

TEST(EchoTest, DirectionsTheArrayCannotTellApartGiveNoEvidence) {
  // A 4-microphone board (8.1 cm) cannot separate directions 10 degrees apart: its beams pass
  // each other's direction at every frequency up to 8 kHz.
  const std::vector<Vec3> board = {{0.0405, 0, 0}, {0, 0.0405, 0}, {-0.0405, 0, 0}, {0, -0.0405, 0}};
  auto test = EchoTest::Create(board, TestOptions());
  ASSERT_TRUE(test.ok());
  const std::vector<float> frame = PlaneWaveFrame(SceneOn(board), Sources(true), 1);
  test->Load(frame.data());
  EchoEvidence e;
  EXPECT_FALSE(test->Compare(AtCone(40.0), AtCone(50.0), &e));
}

TEST(EchoTest, OptionsOutOfRangeAreRefusedByName) {
  EchoTestOptions o = TestOptions();
  o.max_leakage = 1.0;
  EXPECT_NE(EchoTest::Create(Line(), o).status().message().find("max_leakage"), std::string::npos);
  o = TestOptions();
  o.max_delay_s = 0.0;
  EXPECT_NE(EchoTest::Create(Line(), o).status().message().find("max_delay_s"), std::string::npos);
  o = TestOptions();
  o.frame_samples = 1 << 20;  // its spectra would be kept per sensor: refused, not allocated
  EXPECT_NE(EchoTest::Create(Line(), o).status().message().find("frame_samples"), std::string::npos);
  o = TestOptions();
  o.band_high_hz = 9000.0;  // beyond Nyquist at 16 kHz
  EXPECT_EQ(EchoTest::Create(Line(), o).status().code(), StatusCode::kInvalidArgument);
  EXPECT_EQ(EchoTest::Create({Vec3::Zero()}, TestOptions()).status().code(), StatusCode::kInvalidArgument);
  EchoWatchOptions w;
  w.min_envelope_correlation = 2.0;
  auto shape = ClassifyArray(Line());
  ASSERT_TRUE(shape.ok());
  EXPECT_NE(EchoWatch::Create(Line(), *shape, w).status().message().find("min_envelope_correlation"),
            std::string::npos);
}

// Two confirmed tracks on the line at 40 and 75 degrees (cone angles; ids 1 and 2).
std::vector<SourceTrack> Tracks() {
  std::vector<SourceTrack> t(2);
  t[0].id = 1, t[0].status = tws::TrackStatus::kConfirmed, t[0].cone_angle_rad = 40.0 * kDegree;
  t[1].id = 2, t[1].status = tws::TrackStatus::kConfirmed, t[1].cone_angle_rad = 75.0 * kDegree;
  return t;
}

// Feeds `frames` frames of the sources to a watch on the line, both tracks heard from frame
// `both_from` on (before it only track 2 is); returns the frame where track 2 was first called
// an echo (-1: never) and checks that track 1 never is.
int FirstEchoFrame(const std::vector<PlaneSource>& sources, int frames, int both_from = 0) {
  const PlaneWaveScene scene = SceneOn(Line());
  auto shape = ClassifyArray(scene.sensors_m);
  EchoWatchOptions options;
  options.test = TestOptions();
  auto watch = EchoWatch::Create(scene.sensors_m, *shape, options);
  EXPECT_TRUE(watch.ok()) << watch.status().ToString();
  const std::vector<SourceTrack> tracks = Tracks();
  int first = -1;
  for (int i = 0; i < frames; ++i) {
    const std::vector<float> frame = PlaneWaveFrame(scene, sources, 100 + static_cast<uint64_t>(i));
    const std::vector<char> heard = {static_cast<char>(i >= both_from), 1};
    watch->Frame(frame.data(), tracks, heard);
    EXPECT_FALSE(watch->IsEcho(1)) << i;
    if (first < 0 && watch->IsEcho(2)) first = i;
  }
  return first;
}

TEST(EchoWatch, TheWeakerLaggingCopyIsCalledAnEchoAfterMinFrames) {
  const int first = FirstEchoFrame(Sources(true), 30);
  // min_frames consecutive pairs of frames of both: from the ninth frame (index 8) on.
  EXPECT_GE(first, EchoWatchOptions{}.min_frames);
  EXPECT_LE(first, 12);
}

TEST(EchoWatch, IndependentSourcesAreNeverEchoes) { EXPECT_EQ(FirstEchoFrame(Sources(false, 1.0), 60), -1); }

TEST(EchoWatch, ALouderCopyIsNotCalledTheEcho) {
  // gain 1.5: the copy's beam holds more power than its source's. A reflection is weaker.
  EXPECT_EQ(FirstEchoFrame(Sources(true, 1.5), 30), -1);
}

TEST(EchoWatch, ATrackHeardOnItsOwnForFiveFramesHasASourceOfItsOwn) {
  // Track 2 heard without track 1 for 5 frames before both are: never an echo of it.
  EXPECT_EQ(FirstEchoFrame(Sources(true), 30, /*both_from=*/5), -1);
  // Four frames alone is within what a source's missed frames could give: still judged.
  EXPECT_GE(FirstEchoFrame(Sources(true), 30, /*both_from=*/4), 0);
}

TEST(EchoWatch, ViewReportsTheLagAndTheEvidence) {
  const PlaneWaveScene scene = SceneOn(Line());
  auto shape = ClassifyArray(scene.sensors_m);
  EchoWatchOptions options;
  options.test = TestOptions();
  auto watch = EchoWatch::Create(scene.sensors_m, *shape, options);
  ASSERT_TRUE(watch.ok());
  for (int i = 0; i < 20; ++i) {
    const std::vector<float> frame = PlaneWaveFrame(scene, Sources(true), 200 + static_cast<uint64_t>(i));
    watch->Frame(frame.data(), Tracks(), {1, 1});
  }
  EchoWatch::PairView view;
  ASSERT_TRUE(watch->View(1, 2, &view));
  EXPECT_EQ(view.frames, 20);
  EXPECT_NEAR(view.best_lag, CentroidLag(), 1.0);
  EXPECT_GT(view.best_rho, 0.4);
  EXPECT_LT(view.power_share, 0.5);
  EXPECT_GT(view.envelope_correlation, 0.5);
  EXPECT_FALSE(view.later_independent);
  EchoWatch::PairView reverse;
  ASSERT_TRUE(watch->View(2, 1, &reverse));
  EXPECT_GT(reverse.power_share, 0.5);
  EXPECT_LT(reverse.best_rho, 0.2);
  // A track that is no longer reported takes its pairs with it.
  watch->Frame(PlaneWaveFrame(scene, Sources(true), 300).data(), {Tracks()[0]}, {1});
  EXPECT_FALSE(watch->View(1, 2, &view));
  EXPECT_FALSE(watch->IsEcho(2));
}

}  // namespace
}  // namespace localizer::engine
