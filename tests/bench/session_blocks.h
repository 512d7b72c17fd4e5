// Shared by the whole-session benchmarks (pipeline_bench, cost_sweep_bench): a simulated
// recording cut into the blocks a streaming client sends, and one session run over them
// with its per-frame stage timings summed.
#pragma once

#include <algorithm>
#include <cstdint>
#include <vector>

#include "engine/pipeline/session.h"
#include "engine/sim/simulator.h"

namespace localizer::engine::bench {

// Channel-major blocks of `block_samples` per channel; a last partial block is dropped.
inline std::vector<std::vector<float>> SplitIntoBlocks(const SimResult& sim, int64_t block_samples) {
  std::vector<std::vector<float>> blocks;
  for (int64_t at = 0; at + block_samples <= sim.samples_per_channel; at += block_samples) {
    std::vector<float> b(static_cast<size_t>(block_samples * sim.channel_count));
    for (int c = 0; c < sim.channel_count; ++c) {
      std::copy_n(sim.samples.begin() + c * sim.samples_per_channel + at, block_samples,
                  b.begin() + c * block_samples);
    }
    blocks.push_back(std::move(b));
  }
  return blocks;
}

struct StageTotals {
  double tdoa_s = 0.0;
  double filter_s = 0.0;
  size_t frames = 0;
};

// Feeds every block to `session` (sequence numbers from 1) and adds its estimates' timings.
inline void RunBlocks(Session& session, const std::vector<std::vector<float>>& blocks, int channels,
                      int64_t block_samples, std::vector<Estimate>* out, StageTotals* totals) {
  out->clear();
  uint64_t seq = 1;
  for (const auto& b : blocks) (void)session.Process({seq++, channels, block_samples, b.data()}, out);
  for (const Estimate& e : *out) {
    totals->tdoa_s += e.timings.tdoa_s;
    totals->filter_s += e.timings.filter_s;
  }
  totals->frames += out->size();
}

}  // namespace localizer::engine::bench
