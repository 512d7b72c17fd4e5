// std::vector whose storage starts on a cache line (64 bytes), for arrays that vectorised
// loops stream through: with malloc's 16-byte alignment a 512-bit load straddles two lines
// in three of four positions, and where a buffer lands then sets a loop's speed (the
// particle filter's columns: 6.8 -> 6.6 ns per particle-step, BENCHMARKS.md).
//
//   AlignedVector<float> column(n);  // column.data() % 64 == 0
#pragma once

#include <atomic>
#include <cstddef>
#include <new>
#include <vector>

namespace localizer::engine {

template <typename T, std::size_t kAlignBytes = 64>
struct AlignedAllocator {
  using value_type = T;
  static_assert(kAlignBytes >= alignof(T) && (kAlignBytes & (kAlignBytes - 1)) == 0);
  template <typename U>
  struct rebind {
    using other = AlignedAllocator<U, kAlignBytes>;
  };
  AlignedAllocator() = default;
  template <typename U>
  explicit AlignedAllocator(const AlignedAllocator<U, kAlignBytes>&) {}
  T* allocate(std::size_t n) { return static_cast<T*>(::operator new(n * sizeof(T), std::align_val_t(kAlignBytes))); }
  void deallocate(T* p, std::size_t) { ::operator delete(p, std::align_val_t(kAlignBytes)); }
  template <typename U>
  bool operator==(const AlignedAllocator<U, kAlignBytes>&) const {
    return true;
  }
};

template <typename T>
using AlignedVector = std::vector<T, AlignedAllocator<T>>;

}  // namespace localizer::engine
