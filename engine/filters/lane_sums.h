// Sums over the particles with a fixed number of lanes, written out so that the result does
// not depend on the vector width the compiler picks (internal to engine/filters).
//
// An `omp simd reduction(+ : s)` loop sums in as many lanes as its vectors hold: GCC keeps a
// private copy of s per lane, lane k adds the terms i = k (mod VF) of the whole vectors in
// order, the remainder's terms go to lane 0 in order, and the result is
// ((s + lane 0) + lane 1) + ... + lane VF-1. So the sum, and every random path it feeds,
// changes with the vector width (8 floats at 256 bits, 16 at 512). LaneSums spells out that
// order for a fixed lane count: with kLanes = 8 for float (4 for double) it is bit for bit what
// the 256-bit build's reductions computed, and it stays so when the file is compiled for
// 512-bit vectors (particle_set.cc, particle_motion.cc and particle_resampling.cc are; engine/CMakeLists.txt).
//
// Write each term's multiply-add as the reduction loop's compiled code did it: GCC contracts
// `s += a * b` into one fused multiply-add only where every use of a * b can fuse, and that
// decision differs between code shapes, so spell the fused ones `FusedMulAdd(a, b, s)` and
// the others as a product kept in a variable, then added. The whole blocks' inner loop is one
// vector of kLanes (256 bits): a reduction's chain stays as long as before, while the loops
// around it may use 512-bit vectors.
#pragma once

namespace localizer::engine {

// a * b + c in one rounding where the target has a fused multiply-add (where GCC contracted
// the reduction loops' `s += a * b`), else a product and a sum (and never a library call).
inline float FusedMulAdd(float a, float b, float c) {
#if defined(__FP_FAST_FMAF)
  return __builtin_fmaf(a, b, c);
#else
  return a * b + c;
#endif
}

template <typename T>
inline constexpr int kSumLanes = 32 / static_cast<int>(sizeof(T));  // a 256-bit vector's lanes

// out[t] = init[t] + sum over i in [first, end) of the terms body(i, lane, acc) adds to
// acc[t][lane], in the lane order described above (lanes counted from `first`).
template <typename T, int kSums, typename Body>
inline void LaneSums(int first, int end, const T (&init)[kSums], Body body, T (&out)[kSums]) {
  constexpr int kLanes = kSumLanes<T>;
  T acc[kSums][kLanes];
  for (int t = 0; t < kSums; ++t) {
    for (int k = 0; k < kLanes; ++k) acc[t][k] = T(0);
  }
  int i = first;
  for (; i + kLanes <= end; i += kLanes) {
#pragma omp simd
    for (int k = 0; k < kLanes; ++k) body(i + k, k, acc);
  }
  for (; i < end; ++i) body(i, 0, acc);
  for (int t = 0; t < kSums; ++t) {
    T s = init[t];
    for (int k = 0; k < kLanes; ++k) s += acc[t][k];
    out[t] = s;
  }
}

}  // namespace localizer::engine
