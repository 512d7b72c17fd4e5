// Owning wrappers for FFTW3 single-precision buffers and real 1-D plans.
//
// FFTW's planner (plan creation and destruction) is not thread-safe; fftwf_execute* is.
// Every plan made or destroyed here holds FftwPlannerMutex(), so estimators may be created
// and destroyed on any thread. Code elsewhere in the process that calls the FFTW planner
// directly should take the same mutex.
//
// Buffers come from fftwf_malloc (SIMD-aligned) and are zero-filled on allocation. Complex
// data is stored interleaved (re, im) as floats, bit-compatible with fftwf_complex.
//
// Built-in wisdom: before a size's first plan in the process, PlanRealForward/Inverse and
// PlanComplex import that size's FFTW wisdom, generated at build time (engine/tdoa/wisdom_gen)
// for the FFTW_ESTIMATE plans (r2c, c2r and both complex directions) of every size
// NextFastFftSize returns from 64 to 2^21, one entry per size. FFTW then takes a plan from it
// in about 0.1 ms instead of estimating one (2-10 ms per size, the larger part of
// `localizer-cli track`'s start-up after library loading); importing only the sizes planned,
// not all 46, saves ~0.9 ms of a short track's start-up. The plans are the ones FFTW_ESTIMATE
// picks without wisdom on the build machine (tests/tdoa/fftw_wisdom_test), so results do not
// change. Wisdom FFTW cannot use (another FFTW version, a solver the CPU lacks) is refused or
// ignored by FFTW, which then estimates as before. Every engine user in the process (CLI,
// server, Python bindings) plans from the same wisdom, so their results stay bit-identical.
// FFTW_MEASURE requests are not satisfied by it and are measured as before.
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

// Imports the built-in wisdom of every size now (each size's is otherwise imported lazily by
// its first plan). Returns false when this build has none (LOCALIZER_FFTW_WISDOM off, or
// cross-compiled) or FFTW refused an entry. For tests, after ForgetFftwWisdom.
bool ImportBuiltinFftwWisdom();
// Imports size n's built-in wisdom alone; false when there is none for n or FFTW refused it.
bool ImportBuiltinFftwWisdom(int n);
// Forgets all of FFTW's wisdom, and no size's built-in wisdom is imported lazily any more:
// later plans are estimated until ImportBuiltinFftwWisdom. For tests that compare plans made
// with and without it.
void ForgetFftwWisdom();

// Real-to-complex and complex-to-real plans of size n (unnormalised, as FFTW defines them).
// The arrays must not overlap. Planning with FFTW_MEASURE overwrites them.
// A null plan means FFTW could not plan the transform.
FftwPlan PlanRealForward(int n, float* in, float* out_interleaved, unsigned flags);
FftwPlan PlanRealInverse(int n, float* in_interleaved, float* out, unsigned flags);
// A complex 1-D plan of size n, out of place (it then preserves its input); sign is
// FFTW_FORWARD or FFTW_BACKWARD (packed_transforms.h packs two real transforms into one).
FftwPlan PlanComplex(int n, float* in_interleaved, float* out_interleaved, int sign, unsigned flags);

// Smallest n' >= n (n >= 1) of the form 2^a, 3 * 2^a or 5 * 2^a. With FFTW_ESTIMATE plans
// these ran fastest here: an r2c + c2r pair took 12.9 us at 5120, 14.6 at 4608, 17.8 at
// 4320 (2^5 3^3 5) and 26.7 at 8192 (/tmp benchmark, Zen 4, Debian's FFTW 3.3.10).
int NextFastFftSize(int n);

}  // namespace localizer::engine
