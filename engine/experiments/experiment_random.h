// Random engines and Gaussian draws of the experiments, reproducible bit for bit.
//
// Every random draw of a Monte-Carlo run comes from an engine keyed by (experiment seed,
// stream, run index), so that a run replays alone and no stream's draws shift another's.
// Uniforms and normals are built from the engine's 64-bit outputs by fixed arithmetic
// (not std:: distributions, whose algorithms differ between standard libraries), so a seed
// gives the same numbers on every platform. Header-only, no state beyond the engine.
#pragma once

#include <cmath>
#include <cstdint>
#include <numbers>
#include <random>

namespace localizer::engine::experiments {

enum class ExperimentStream : uint32_t {
  kControlNoise = 1,      // the truth's speed and steering errors
  kMeasurementNoise = 2,  // the mixture noise of the position fixes
  kFilter = 3,            // a filter's own draws (particles); the filter index is mixed in
};

// std::mt19937_64 seeded by std::seed_seq over the 32-bit halves of seed and run, the
// stream and a sub-index (which filter, for kFilter).
inline std::mt19937_64 ExperimentEngine(uint64_t seed, ExperimentStream stream, int64_t run, uint32_t sub_index = 0) {
  const auto r = static_cast<uint64_t>(run);
  std::seed_seq sequence{static_cast<uint32_t>(seed), static_cast<uint32_t>(seed >> 32), static_cast<uint32_t>(stream),
                         static_cast<uint32_t>(r),    static_cast<uint32_t>(r >> 32),    sub_index};
  return std::mt19937_64(sequence);
}

// (k + 1/2) 2^-52 for the top 52 bits k of one output: in (0, 1), never 0 or 1.
inline double OpenUniform(std::mt19937_64& engine) {
  const uint64_t k = engine() >> 12;
  return (static_cast<double>(k) + 0.5) * 0x1p-52;
}

// N(0, 1) by Box-Muller from two outputs (the cosine branch only: simpler than caching the
// sine branch, and draws stay independent of call order within a stream).
inline double StandardNormal(std::mt19937_64& engine) {
  const double radius = std::sqrt(-2.0 * std::log(OpenUniform(engine)));
  return radius * std::cos(2.0 * std::numbers::pi * OpenUniform(engine));
}

}  // namespace localizer::engine::experiments
