// The real XAV recordings (Mouy et al. 2023, BSD 3-Clause) track end to end through
// engine::Session by way of io::RunTrack, the code behind `localizer-cli track`. There is
// no ground truth: the checks are that nothing valid is rejected, the frame count is
// exact, every value is finite, and fixes whose frame bounds the range stay near the array
// (fish call within a few metres of it; 50 m is a loose bound that a diverged or mirrored
// track would break). A far-field fix (Estimate::far_field: the frame gives a direction, not
// a range; the quiet periods' distant source) may lie further out, and says so.
#include <gtest/gtest.h>

#include <cmath>

#include "clients/io/track_runner.h"
#include "clients/io/xav_array.h"
#include "tests/clients/test_util.h"

namespace localizer::io {
namespace {

TEST(XavTrack, WholeRecordingTracksWithoutRejectionAndStaysNearTheArray) {
  auto xav = ReadXavHydrophoneCsv(testing::XavConfigCsv());
  ASSERT_TRUE(xav.ok()) << xav.status().ToString();
  auto paths = FindXavRecordings(testing::XavDir(), xav->file_name_roots);
  ASSERT_TRUE(paths.ok()) << paths.status().ToString();

  TrackJob job;
  job.wav_paths = *paths;
  job.array_source = testing::XavConfigCsv();
  job.array_sample_rate_hz = xav->array.sample_rate_hz;
  job.config.sensors_m = xav->array.sensors_m;
  job.config.sound_speed_mps = xav->array.sound_speed_mps;
  job.config.reference_sensor = xav->array.reference_sensor;
  job.config.frame_samples = 4096;
  job.config.hop_samples = 2048;
  job.config.tracker.particle.particles = 1024;  // keeps the test quick; accuracy is not asserted
  // The authors' detector looks at 0-1000 Hz (detection_config_large_array.yaml): fish
  // grunts and knocks. Outside that band PHAT would whiten 31 kHz of ambient noise.
  job.config.band_low_hz = 50.0;
  job.config.band_high_hz = 1000.0;
  job.config.seed = 7;

  std::vector<engine::Estimate> estimates;
  std::vector<std::string> warnings;
  TrackCallbacks callbacks;
  callbacks.on_estimate = [&](const engine::Estimate& e) { estimates.push_back(e); };
  callbacks.on_warning = [&](const std::string& w) { warnings.push_back(w); };
  auto summary = RunTrack(job, callbacks);
  ASSERT_TRUE(summary.ok()) << summary.status().ToString();  // every block accepted

  const int64_t frames = summary->samples_per_channel;
  EXPECT_EQ(summary->sample_rate_hz, 32000.0);
  EXPECT_EQ(summary->channel_count, 6);
  EXPECT_GT(frames, 16 * 32000);
  const int64_t expected = (frames - job.config.frame_samples) / job.config.hop_samples + 1;
  EXPECT_EQ(static_cast<int64_t>(estimates.size()), expected);
  EXPECT_EQ(static_cast<int64_t>(summary->estimates), expected);
  ASSERT_EQ(warnings.size(), 1u) << "only the 230-sample truncation is expected";
  EXPECT_NE(warnings[0].find("truncated"), std::string::npos);

  engine::Vec3 centroid = engine::Vec3::Zero();
  for (const engine::Vec3& m : xav->array.sensors_m) centroid += m / 6.0;
  int initialised = 0, far_field = 0;
  for (size_t i = 0; i < estimates.size(); ++i) {
    const engine::Estimate& e = estimates[i];
    EXPECT_EQ(e.frame_index, i);
    ASSERT_TRUE(std::isfinite(e.t_s));
    ASSERT_TRUE(e.state.allFinite()) << "frame " << i;
    ASSERT_TRUE(e.covariance.allFinite()) << "frame " << i;
    if (i > 0) {
      EXPECT_GT(e.t_s, estimates[i - 1].t_s);
    }
    if (!e.initialised) continue;
    ++initialised;
    far_field += e.far_field;
    const double range_m = (e.state.head<3>() - centroid).norm();
    if (!e.far_field) {
      EXPECT_LT(range_m, 50.0) << "frame " << i << " at t = " << e.t_s << " s";
    }
  }
  std::printf("XAV: %zu frames, %d initialised, %d far field\n", estimates.size(), initialised, far_field);
}

}  // namespace
}  // namespace localizer::io
