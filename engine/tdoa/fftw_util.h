// Owning wrappers for FFTW3 single-precision buffers and real 1-D plans.
//
// FFTW's planner (plan creation and destruction) is not thread-safe; fftwf_execute* is.
// Every plan made or destroyed here holds FftwPlannerMutex(), so estimators may be created
// and destroyed on any thread. Code elsewhere in the process that calls the FFTW planner
// directly should take the same mutex.
//
// Buffers come from fftwf_malloc (SIMD-aligned) and are zero-filled on allocation. Complex
// data is stored interleaved (re, im) as floats, bit-compatible with fftwf_complex.
#pragma once

#include <fftw3.h>

#include <cstddef>
#include <memory>
#include <mutex>

namespace localizer::engine {

std::mutex& FftwPlannerMutex();

struct FftwFree {
  void operator()(float* p) const { fftwf_free(p); }
};
using FftwFloats = std::unique_ptr<float[], FftwFree>;

// `count` zeroed floats, SIMD-aligned. Aborts (like operator new) when memory runs out.
FftwFloats AllocateFftwFloats(std::size_t count);

inline fftwf_complex* AsComplex(float* interleaved) { return reinterpret_cast<fftwf_complex*>(interleaved); }

// A move-only fftwf_plan.
class FftwPlan {
 public:
  FftwPlan() = default;
  explicit FftwPlan(fftwf_plan plan) : plan_(plan) {}
  FftwPlan(FftwPlan&& other) noexcept : plan_(other.plan_) { other.plan_ = nullptr; }
  FftwPlan& operator=(FftwPlan&& other) noexcept;
  FftwPlan(const FftwPlan&) = delete;
  FftwPlan& operator=(const FftwPlan&) = delete;
  ~FftwPlan() { Reset(); }

  fftwf_plan get() const { return plan_; }
  explicit operator bool() const { return plan_ != nullptr; }

 private:
  void Reset();
  fftwf_plan plan_ = nullptr;
};

// Real-to-complex and complex-to-real plans of size n (unnormalised, as FFTW defines them).
// The arrays must not overlap. Planning with FFTW_MEASURE overwrites them.
// A null plan means FFTW could not plan the transform.
FftwPlan PlanRealForward(int n, float* in, float* out_interleaved, unsigned flags);
FftwPlan PlanRealInverse(int n, float* in_interleaved, float* out, unsigned flags);

// Smallest n' >= n (n >= 1) of the form 2^a, 3 * 2^a or 5 * 2^a. With FFTW_ESTIMATE plans
// these ran fastest here: an r2c + c2r pair took 12.9 us at 5120, 14.6 at 4608, 17.8 at
// 4320 (2^5 3^3 5) and 26.7 at 8192 (/tmp benchmark, Zen 4, Debian's FFTW 3.3.10).
int NextFastFftSize(int n);

}  // namespace localizer::engine
