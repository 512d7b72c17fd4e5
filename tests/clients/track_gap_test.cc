// Samples a live input lost (a capture overrun) are skipped in the session by the runner
// (io::RunTrackOn, track_runner.h), so the estimates after the gap carry the times of their
// samples. A stand-in input serves a simulated scene (tetra-water, 8 s, seed 1) with a stretch
// cut out and reported as lost, as AlsaCaptureStream reports an overrun; the run on it is
// compared with the run on the whole scene (same filter seed).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <vector>

#include "clients/io/simulation_files.h"
#include "clients/io/track_runner.h"

namespace localizer::io {
namespace {

// The scene's samples, minus [cut_begin, cut_begin + cut_frames) when cut_frames > 0: the
// block that reaches the cut ends there and the next reports the cut as lost.
class CutStream final : public SampleStream {
 public:
  CutStream(const engine::SimResult& scene, int64_t cut_begin, int64_t cut_frames)
      : scene_(scene), cut_begin_(cut_begin), cut_frames_(cut_frames) {}
  double sample_rate_hz() const override { return scene_.sample_rate_hz; }
  int channel_count() const override { return scene_.channel_count; }
  int64_t total_frames() const override { return 0; }
  std::string Describe() const override { return "the scene with a cut"; }
  std::string RateOrigin() const override { return "the simulator"; }
  int64_t frames_lost_before_last_read() const override { return gap_before_; }
  int64_t overrun_count() const override { return cut_frames_ > 0 && position_ > cut_begin_ ? 1 : 0; }
  int64_t frames_lost() const override { return cut_frames_ > 0 && position_ > cut_begin_ ? cut_frames_ : 0; }

  StatusOr<int64_t> Read(int64_t max_frames, std::vector<float>* out) override {
    gap_before_ = 0;
    if (cut_frames_ > 0 && position_ == cut_begin_) {
      position_ += cut_frames_;
      gap_before_ = cut_frames_;
    }
    int64_t n = std::min(max_frames, scene_.samples_per_channel - position_);
    if (cut_frames_ > 0 && position_ < cut_begin_) n = std::min(n, cut_begin_ - position_);
    out->resize(static_cast<size_t>(n) * scene_.channel_count);
    for (int c = 0; c < scene_.channel_count; ++c) {
      const float* from = scene_.samples.data() + c * scene_.samples_per_channel + position_;
      std::copy(from, from + n, out->begin() + c * n);
    }
    position_ += n;
    return n;
  }

 private:
  const engine::SimResult& scene_;
  int64_t cut_begin_;
  int64_t cut_frames_;
  int64_t position_ = 0;
  int64_t gap_before_ = 0;
};

TEST(TrackGap, EstimatesAfterALossKeepTheTimesOfTheirSamples) {
  auto run = SimulateScenario("tetra-water", 1, 8.0);
  ASSERT_TRUE(run.ok()) << run.status().ToString();
  const engine::SimResult& scene = run->result;
  TrackJob job;
  job.config.sensors_m = run->scenario.sensors_m;  // as track reads them from the scene's array.json
  job.config.sound_speed_mps = run->scenario.sound_speed_mps;
  job.config.reference_sensor = run->reference_sensor;
  job.config.band_low_hz = run->scenario.sim.band_low_hz;
  job.config.band_high_hz = run->scenario.sim.band_high_hz;
  job.config.seed = 7;
  const int hop = job.config.hop_samples;
  // Lost: 0.74 s from 3 s in; both ends on the frame grid, so the frames after the gap are
  // frames of the whole run too, and their times can be compared exactly.
  const int64_t cut_begin = 16 * hop;
  const int64_t cut_frames = 4 * hop;

  std::vector<engine::Estimate> whole;
  std::vector<engine::Estimate> cut;
  TrackCallbacks collect_whole;
  collect_whole.on_estimate = [&whole](const engine::Estimate& e) { whole.push_back(e); };
  TrackCallbacks collect_cut;
  collect_cut.on_estimate = [&cut](const engine::Estimate& e) { cut.push_back(e); };
  auto whole_summary = RunTrackOn(std::make_unique<CutStream>(scene, 0, 0), job, collect_whole);
  ASSERT_TRUE(whole_summary.ok()) << whole_summary.status().ToString();
  auto cut_summary = RunTrackOn(std::make_unique<CutStream>(scene, cut_begin, cut_frames), job, collect_cut);
  ASSERT_TRUE(cut_summary.ok()) << cut_summary.status().ToString();

  EXPECT_EQ(cut_summary->frames_lost, cut_frames);
  EXPECT_EQ(cut_summary->overruns, 1);
  EXPECT_EQ(cut_summary->samples_per_channel + cut_frames, whole_summary->samples_per_channel);
  ASSERT_GE(whole.size(), 30u);
  // Every estimate of the cut run is at a time the whole run has an estimate: none shifted by
  // the lost 0.74 s (without the skip every one after the gap would be 0.74 s early), and the
  // last frames line up.
  for (const engine::Estimate& e : cut) {
    const bool found = std::any_of(whole.begin(), whole.end(),
                                   [&e](const engine::Estimate& w) { return std::abs(w.t_s - e.t_s) < 1e-9; });
    EXPECT_TRUE(found) << "t_s " << e.t_s;
  }
  ASSERT_FALSE(cut.empty());
  EXPECT_NEAR(cut.back().t_s, whole.back().t_s, 1e-9);
  // Frames overlapping the lost stretch are missing: the frames whose window lies within it
  // or straddles an end (frame - hop samples, hop apart, each side).
  const int frames_missing = static_cast<int>(whole.size() - cut.size());
  EXPECT_GE(frames_missing, 4);
  EXPECT_LE(frames_missing, 4 + job.config.frame_samples / hop);
  // The tracker predicted across the gap and is back on the source by the end.
  const engine::TruthRow truth = scene.TruthAt(cut.back().t_s);
  EXPECT_LT((cut.back().state.head<3>() - truth.position_m).norm(), 1.0);
}

}  // namespace
}  // namespace localizer::io
