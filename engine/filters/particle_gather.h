// The parents of 16 resampled slots, read column by column (internal to engine/filters:
// ResampleSystematic's one-label pass and ResampleModes' per-label one share it).
#pragma once

#include <array>

namespace localizer::engine {

#if defined(__AVX512F__)
// parent[r][k] = column r of particle index[k], k = 0 .. 15; index is non-decreasing and
// below n. Systematic resampling's indices advance about one particle per slot, so the 16
// parents nearly always lie within 32 consecutive particles: then two loads and one permute
// per column replace a 16-way gather (which costs Zen and Intel cores about one load per
// lane). Either way the same values.
void GatherParents16(const std::array<float*, 6>& from, const int* index, int n, float (*parent)[16]);
#endif

// dst[m] = src[index[m]] for m in [0, n), index non-decreasing and below n (the per-particle
// values that resampling carries, particle_motion.cc); GatherParents16's loads when built
// with AVX-512, a scalar loop otherwise. src and dst must not overlap.
void GatherSorted(const float* src, const int* index, int n, float* dst);

}  // namespace localizer::engine
