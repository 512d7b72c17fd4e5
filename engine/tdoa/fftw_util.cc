#include "engine/tdoa/fftw_util.h"

#include <algorithm>
#include <cstdlib>
#include <cstring>

namespace localizer::engine {

std::mutex& FftwPlannerMutex() {
  static std::mutex mutex;
  return mutex;
}

namespace {

// Generated at build time (engine/CMakeLists.txt, wisdom_gen/fftw_wisdom_gen.cc); "" without.
constexpr const char kBuiltinWisdom[] =
#include "engine/tdoa/fftw_builtin_wisdom.inc"
    ;

// The planner mutex must be held.
bool ImportBuiltinWisdomLocked() {
  return kBuiltinWisdom[0] != '\0' && fftwf_import_wisdom_from_string(kBuiltinWisdom) != 0;
}

// Before the first plan; the planner mutex must be held.
void ImportBuiltinWisdomOnce() {
  static bool imported = false;  // GUARDED_BY(FftwPlannerMutex())
  if (imported) return;
  imported = true;
  ImportBuiltinWisdomLocked();
}

}  // namespace

bool ImportBuiltinFftwWisdom() {
  std::lock_guard<std::mutex> lock(FftwPlannerMutex());
  return ImportBuiltinWisdomLocked();
}

FftwFloats AllocateFftwFloats(std::size_t count) {
  auto* p = static_cast<float*>(fftwf_malloc(count * sizeof(float)));
  if (p == nullptr) std::abort();  // out of memory, as operator new would report it
  std::memset(p, 0, count * sizeof(float));
  return FftwFloats(p);
}

FftwPlan& FftwPlan::operator=(FftwPlan&& other) noexcept {
  if (this != &other) {
    Reset();
    plan_ = other.plan_;
    other.plan_ = nullptr;
  }
  return *this;
}

void FftwPlan::Reset() {
  if (plan_ == nullptr) return;
  std::lock_guard<std::mutex> lock(FftwPlannerMutex());
  fftwf_destroy_plan(plan_);
  plan_ = nullptr;
}

FftwPlan PlanRealForward(int n, float* in, float* out_interleaved, unsigned flags) {
  std::lock_guard<std::mutex> lock(FftwPlannerMutex());
  ImportBuiltinWisdomOnce();
  return FftwPlan(fftwf_plan_dft_r2c_1d(n, in, AsComplex(out_interleaved), flags));
}

FftwPlan PlanRealInverse(int n, float* in_interleaved, float* out, unsigned flags) {
  std::lock_guard<std::mutex> lock(FftwPlannerMutex());
  ImportBuiltinWisdomOnce();
  return FftwPlan(fftwf_plan_dft_c2r_1d(n, AsComplex(in_interleaved), out, flags));
}

int NextFastFftSize(int n) {
  int best = 1;
  while (best < n) best <<= 1;
  for (int odd : {3, 5}) {
    int candidate = odd;
    while (candidate < n) candidate <<= 1;
    best = std::min(best, candidate);
  }
  return best;
}

}  // namespace localizer::engine
