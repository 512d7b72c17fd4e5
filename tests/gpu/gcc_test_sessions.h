// Shared by the GCC batch's device tests (gcc_batch_test.cc, gcc_ring_test.cc): simulated
// sessions with their CPU estimator and GPU plan, frames cut from their recordings with what
// the CPU makes of them, and the comparisons (with the CPU within the batch's promised
// tolerances; with another GPU run bit for bit).
//
// Tolerances (gcc_batch.h's promise, with margin): delay within 1e-3 sample, quality, peak
// value and peak SNR within 1e-3 relative, GCC windows within 1e-4 absolute. cuFFT and FFTW
// round differently (~1e-6 relative); nothing else should differ.
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include "engine/sim/simulator.h"
#include "engine/tdoa/gcc_phat.h"
#include "gpu/tdoa/gcc_batch.h"

namespace localizer::gpu::gcc_testing {

using engine::GccOptions;
using engine::Measurement;
using engine::PeakInterpolation;
using engine::Weighting;

constexpr int kFrameSamples = 4096;

// A session: its array and options, the CPU estimator, the GPU plan, and a simulated
// recording to cut frames from.
struct Session {
  Session(const engine::Scenario& scenario, const GccOptions& gcc_options, double duration_s)
      : array(*engine::ArrayGeometry::Create(scenario.sensors_m, scenario.sound_speed_mps)),
        options(gcc_options),
        plan(*GccPlan::Create(array, options)) {
    auto made = engine::GccPhatEstimator::Create(array, options);
    EXPECT_TRUE(made.ok()) << made.status().ToString();
    if (made.ok()) cpu = std::move(*made);
    engine::SimOptions sim_options = scenario.sim;
    sim_options.duration_s = duration_s;
    auto simulated = engine::Simulate(array, sim_options);
    EXPECT_TRUE(simulated.ok()) << simulated.status().ToString();
    if (simulated.ok()) recording = std::move(*simulated);
  }

  // Channel-major frame of kFrameSamples starting at sample `start` of every channel.
  std::vector<float> Frame(int64_t start) const {
    std::vector<float> frame(static_cast<std::size_t>(recording.channel_count) * kFrameSamples);
    if (start < 0 || start > last_start()) {
      ADD_FAILURE() << "frame at sample " << start << " runs past the recording's " << recording.samples_per_channel;
      return frame;
    }
    for (int c = 0; c < recording.channel_count; ++c) {
      const float* channel = recording.samples.data() + c * recording.samples_per_channel + start;
      std::copy(channel, channel + kFrameSamples, frame.begin() + static_cast<std::ptrdiff_t>(c) * kFrameSamples);
    }
    return frame;
  }
  int64_t last_start() const { return recording.samples_per_channel - kFrameSamples; }

  engine::ArrayGeometry array;
  GccOptions options;
  GccPlan plan;
  std::unique_ptr<engine::GccPhatEstimator> cpu;
  engine::SimResult recording;
};

inline GccOptions Options(double sample_rate_hz, Weighting weighting, PeakInterpolation interpolation,
                          double band_low_hz, double band_high_hz, bool keep_gcc = true) {
  GccOptions o;
  o.frame_samples = kFrameSamples;
  o.sample_rate_hz = sample_rate_hz;
  o.weighting = weighting;
  o.interpolation = interpolation;
  o.band_low_hz = band_low_hz;
  o.band_high_hz = band_high_hz;
  o.keep_gcc = keep_gcc;
  return o;
}

inline std::unique_ptr<Session> MakeSession(const std::string& scenario_name, const GccOptions& options,
                                            double duration_s = 1.0) {
  auto scenario = engine::MakeScenario(scenario_name, 3);
  EXPECT_TRUE(scenario.ok());
  GccOptions o = options;
  o.sample_rate_hz = scenario->sim.sample_rate_hz;
  return std::make_unique<Session>(*scenario, o, duration_s);
}

// One frame to measure, with what the CPU makes of it.
struct Item {
  const Session* session;
  std::vector<float> frame;
  double t_s;
  Measurement cpu;
};

inline Item MakeItem(Session& session, int64_t start) {
  const int64_t centre = start + kFrameSamples / 2;  // the frame's centre sample (kFrameSamples is even)
  Item item{&session, session.Frame(start), static_cast<double>(centre) / session.options.sample_rate_hz, {}};
  EXPECT_TRUE(session.cpu->Estimate(item.frame.data(), kFrameSamples, item.t_s, &item.cpu).ok());
  return item;
}

// `count` frames of `session`, spread over its recording.
inline std::vector<Item> SpreadItems(Session& session, int count) {
  std::vector<Item> items;
  for (int i = 0; i < count; ++i) items.push_back(MakeItem(session, session.last_start() * i / std::max(1, count - 1)));
  return items;
}

inline std::vector<Measurement> RunOnGpu(GccBatch& batch, const std::vector<Item>& items) {
  std::vector<Measurement> out(items.size());
  std::vector<GccJob> jobs;
  for (std::size_t i = 0; i < items.size(); ++i) {
    jobs.push_back({&items[i].session->plan, items[i].frame.data(), items[i].t_s, &out[i]});
  }
  const Status status = batch.Run(jobs);
  EXPECT_TRUE(status.ok()) << status.ToString();
  return out;
}

inline double Relative(double a, double b) { return std::abs(a - b) / std::max({std::abs(a), std::abs(b), 1e-12}); }

inline void ExpectMatchesCpu(const Measurement& gpu, const Measurement& cpu) {
  EXPECT_EQ(gpu.t_s, cpu.t_s);
  EXPECT_EQ(gpu.sample_rate_hz, cpu.sample_rate_hz);
  ASSERT_EQ(gpu.pairs.size(), cpu.pairs.size());
  const double fs = cpu.sample_rate_hz;
  for (std::size_t p = 0; p < cpu.pairs.size(); ++p) {
    SCOPED_TRACE("pair " + std::to_string(p));
    const engine::PairMeasurement& g = gpu.pairs[p];
    const engine::PairMeasurement& c = cpu.pairs[p];
    EXPECT_EQ(g.sensor, c.sensor);
    EXPECT_EQ(g.first_lag_samples, c.first_lag_samples);
    EXPECT_NEAR(g.delay_s * fs, c.delay_s * fs, 1e-3);
    EXPECT_LE(Relative(g.quality, c.quality), 1e-3) << g.quality << " vs " << c.quality;
    EXPECT_LE(Relative(g.peak_value, c.peak_value), 1e-3) << g.peak_value << " vs " << c.peak_value;
    EXPECT_LE(Relative(g.peak_snr, c.peak_snr), 1e-3);
    EXPECT_LE(Relative(g.delay_sigma_s, c.delay_sigma_s), 1e-3) << g.delay_sigma_s << " vs " << c.delay_sigma_s;
    // Without a kept window the batch has no other extrema to pick: the main peak alone.
    const std::size_t want_candidates =
        c.gcc.empty() ? std::min<std::size_t>(c.candidates.size(), 1) : c.candidates.size();
    ASSERT_EQ(g.candidates.size(), want_candidates);
    for (std::size_t k = 0; k < want_candidates; ++k) {
      SCOPED_TRACE("candidate " + std::to_string(k));
      EXPECT_NEAR(g.candidates[k].delay_s * fs, c.candidates[k].delay_s * fs, 1e-3);
      EXPECT_NEAR(g.candidates[k].value, c.candidates[k].value, 1e-4);
      EXPECT_LE(Relative(g.candidates[k].delay_sigma_s, c.candidates[k].delay_sigma_s), 1e-2);
    }
    ASSERT_EQ(g.gcc.size(), c.gcc.size());
    float worst = 0.0f;
    for (std::size_t i = 0; i < c.gcc.size(); ++i) worst = std::max(worst, std::abs(g.gcc[i] - c.gcc[i]));
    EXPECT_LE(worst, 1e-4f);
  }
}

inline void ExpectAllMatchCpu(const std::vector<Measurement>& gpu, const std::vector<Item>& items) {
  ASSERT_EQ(gpu.size(), items.size());
  for (std::size_t i = 0; i < items.size(); ++i) {
    SCOPED_TRACE("job " + std::to_string(i));
    ExpectMatchesCpu(gpu[i], items[i].cpu);
  }
}

inline void ExpectIdentical(const Measurement& a, const Measurement& b) {
  EXPECT_EQ(a.t_s, b.t_s);
  ASSERT_EQ(a.pairs.size(), b.pairs.size());
  for (std::size_t p = 0; p < a.pairs.size(); ++p) {
    EXPECT_EQ(a.pairs[p].delay_s, b.pairs[p].delay_s);
    EXPECT_EQ(a.pairs[p].quality, b.pairs[p].quality);
    EXPECT_EQ(a.pairs[p].peak_value, b.pairs[p].peak_value);
    EXPECT_EQ(a.pairs[p].peak_snr, b.pairs[p].peak_snr);
    EXPECT_EQ(a.pairs[p].delay_sigma_s, b.pairs[p].delay_sigma_s);
    ASSERT_EQ(a.pairs[p].candidates.size(), b.pairs[p].candidates.size());
    for (std::size_t k = 0; k < a.pairs[p].candidates.size(); ++k) {
      EXPECT_EQ(a.pairs[p].candidates[k].delay_s, b.pairs[p].candidates[k].delay_s);
      EXPECT_EQ(a.pairs[p].candidates[k].delay_sigma_s, b.pairs[p].candidates[k].delay_sigma_s);
    }
    EXPECT_EQ(a.pairs[p].gcc, b.pairs[p].gcc);
  }
}

inline std::unique_ptr<GccBatch> MakeBatch(const GccPlan& plan, int max_frames, bool timing = false) {
  auto batch = GccBatch::Create(plan.key(), max_frames, timing);
  EXPECT_TRUE(batch.ok()) << batch.status().ToString();
  return batch.ok() ? std::move(*batch) : nullptr;
}

}  // namespace localizer::gpu::gcc_testing
