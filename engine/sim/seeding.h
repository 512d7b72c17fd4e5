// Random engines for the simulator, one per (seed, stream, index), so that each draw depends
// only on what it is for and never on how many draws came before it elsewhere.
#pragma once

#include <cstdint>
#include <random>

namespace localizer::engine {

enum class RandomStream : uint32_t {
  kSourceNoise = 1,      // index: block of source samples
  kClickJitter = 2,      // index: nominal click number
  kChannelNoise = 3,     // index: channel
  kChannelImpulses = 4,  // index: channel
  kTones = 5,            // index: 0 (the tones' frequencies and phases)
};

// std::mt19937_64 seeded by std::seed_seq over the 32-bit halves of seed and index, and the
// stream: deterministic across platforms (the distributions drawn from it are the standard
// library's, deterministic within one build).
inline std::mt19937_64 SeededEngine(uint64_t seed, RandomStream stream, int64_t index) {
  const auto u = static_cast<uint64_t>(index);
  std::seed_seq sequence{static_cast<uint32_t>(seed), static_cast<uint32_t>(seed >> 32), static_cast<uint32_t>(stream),
                         static_cast<uint32_t>(u), static_cast<uint32_t>(u >> 32)};
  return std::mt19937_64(sequence);
}

}  // namespace localizer::engine
