// Where a bank slot's arrays live inside its one device allocation, and how many bytes it
// takes: the figure Open checks against the bank's memory limit.
//
// Per particle: two state buffers (2 x 6 floats: the current one and the resampling target),
// log-weight and weight (2 floats), a double for the prefix sums of resampling: 64 bytes;
// per block of kBlockThreads particles one BlockPartial (~0.3 KB). Each array starts on a
// 256-byte boundary (coalesced, and what cudaMalloc itself guarantees for the base).
#pragma once

#include <cstddef>

#include "gpu/filters/pf_kernels.h"

namespace localizer::gpu::pf {

struct SlotLayout {
  int particles = 0;
  int blocks = 0;
  std::size_t state[2][6] = {};  // byte offsets of the two buffers' columns
  std::size_t logw = 0, w = 0, cumsum = 0, partials = 0;
  std::size_t bytes = 0;  // the allocation's size

  static SlotLayout For(int particles) {
    constexpr std::size_t kAlign = 256;
    const auto align = [](std::size_t x) { return (x + kAlign - 1) / kAlign * kAlign; };
    SlotLayout l;
    l.particles = particles;
    l.blocks = (particles + kBlockThreads - 1) / kBlockThreads;
    const std::size_t n = static_cast<std::size_t>(particles);
    std::size_t at = 0;
    for (auto& buffer : l.state) {
      for (std::size_t& column : buffer) {
        column = at;
        at = align(at + n * sizeof(float));
      }
    }
    l.logw = at;
    at = align(at + n * sizeof(float));
    l.w = at;
    at = align(at + n * sizeof(float));
    l.cumsum = at;
    at = align(at + n * sizeof(double));
    l.partials = at;
    at = align(at + static_cast<std::size_t>(l.blocks) * sizeof(BlockPartial));
    l.bytes = at;
    return l;
  }

  // The device arrays of a slot whose allocation starts at `base`, with state buffer
  // `current` (0 or 1) as the current one.
  SlotView View(unsigned char* base, int current) const {
    SlotView v;
    for (int c = 0; c < 6; ++c) {
      v.state[c] = reinterpret_cast<float*>(base + state[current][c]);
      v.next[c] = reinterpret_cast<float*>(base + state[1 - current][c]);
    }
    v.logw = reinterpret_cast<float*>(base + logw);
    v.w = reinterpret_cast<float*>(base + w);
    v.cumsum = reinterpret_cast<double*>(base + cumsum);
    v.partials = reinterpret_cast<BlockPartial*>(base + partials);
    v.particles = particles;
    v.blocks = blocks;
    return v;
  }
};

}  // namespace localizer::gpu::pf
