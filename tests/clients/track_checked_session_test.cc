// io::RunTrack may run a session its caller already built from the job's config (the CLI's
// configuration check builds one; track_runner.h). Sessions are seeded, so that session and a
// fresh one must give the same estimates bit for bit; a session built at another sample rate
// than the input's is not used.
#include <gtest/gtest.h>

#include <memory>
#include <vector>

#include "clients/io/simulation_files.h"
#include "clients/io/track_runner.h"
#include "clients/io/wav_io.h"
#include "tests/clients/test_util.h"

namespace localizer::io {
namespace {

using testing::TempDir;

struct TrackRun {
  std::vector<engine::Estimate> estimates;
  TrackSummary summary;
};

TrackRun Track(const TrackJob& job, std::unique_ptr<engine::Session> session) {
  TrackRun run;
  TrackCallbacks callbacks;
  callbacks.on_estimate = [&run](const engine::Estimate& e) { run.estimates.push_back(e); };
  auto summary = RunTrack(job, callbacks, std::move(session));
  EXPECT_TRUE(summary.ok()) << summary.status().ToString();
  if (summary.ok()) run.summary = *summary;
  return run;
}

void ExpectSameEstimates(const TrackRun& a, const TrackRun& b) {
  ASSERT_EQ(a.estimates.size(), b.estimates.size());
  for (size_t i = 0; i < a.estimates.size(); ++i) {
    const engine::Estimate& x = a.estimates[i];
    const engine::Estimate& y = b.estimates[i];
    ASSERT_EQ(x.t_s, y.t_s) << i;
    ASSERT_EQ(x.initialised, y.initialised) << i;
    ASSERT_EQ(x.state, y.state) << "frame " << i;  // exact: the same seeded session
    ASSERT_EQ(x.covariance, y.covariance) << "frame " << i;
  }
}

TEST(TrackCheckedSession, ASessionBuiltFromTheJobGivesTheEstimatesOfAFreshOne) {
  auto sim = SimulateScenario("tetra-water", 3, 4.0);
  ASSERT_TRUE(sim.ok()) << sim.status().ToString();
  TempDir dir;
  Recording recording;
  recording.sample_rate_hz = sim->result.sample_rate_hz;
  recording.channel_count = sim->result.channel_count;
  recording.frames = sim->result.samples_per_channel;
  recording.samples = sim->result.samples;
  ASSERT_TRUE(WriteWavFloat(dir.File("scene.wav"), recording).ok());

  TrackJob job;
  job.wav_paths = {dir.File("scene.wav")};
  job.config.sensors_m = sim->scenario.sensors_m;
  job.config.sound_speed_mps = sim->scenario.sound_speed_mps;
  job.config.reference_sensor = sim->reference_sensor;
  job.config.band_low_hz = sim->scenario.sim.band_low_hz;
  job.config.band_high_hz = sim->scenario.sim.band_high_hz;
  job.config.sample_rate_hz = recording.sample_rate_hz;
  job.config.seed = 5;

  const TrackRun fresh = Track(job, nullptr);
  ASSERT_GE(fresh.estimates.size(), 20u);
  ASSERT_TRUE(fresh.estimates.back().initialised);

  auto checked = engine::Session::Create(job.config);
  ASSERT_TRUE(checked.ok()) << checked.status().ToString();
  const TrackRun reused = Track(job, std::move(*checked));
  ExpectSameEstimates(fresh, reused);

  // The given session is the one run (the runner trusts its caller that it was built from
  // the job's config, and checks only the rate): one seeded otherwise gives that seed's run.
  TrackJob seed6 = job;
  seed6.config.seed = 6;
  const TrackRun fresh6 = Track(seed6, nullptr);
  ASSERT_NE(fresh6.estimates.back().state, fresh.estimates.back().state);
  auto other_seed = engine::Session::Create(seed6.config);
  ASSERT_TRUE(other_seed.ok()) << other_seed.status().ToString();
  ExpectSameEstimates(fresh6, Track(job, std::move(*other_seed)));

  // Built for another rate: not the input's session, so the runner builds its own and the
  // estimates are still the fresh run's (with that session they would differ: its band
  // edges, frame times and delays in samples are another rate's).
  engine::AudioSessionConfig other = job.config;
  other.sample_rate_hz = 2.0 * recording.sample_rate_hz;
  auto wrong_rate = engine::Session::Create(other);
  ASSERT_TRUE(wrong_rate.ok()) << wrong_rate.status().ToString();
  const TrackRun replaced = Track(job, std::move(*wrong_rate));
  ExpectSameEstimates(fresh, replaced);
}

}  // namespace
}  // namespace localizer::io
