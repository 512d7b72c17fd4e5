#include "engine/tdoa/fftw_util.h"

#include <algorithm>
#include <array>
#include <cstdlib>
#include <cstring>
#include <iterator>

namespace localizer::engine {

std::mutex& FftwPlannerMutex() {
  static std::mutex mutex;
  return mutex;
}

namespace {

// One size's wisdom: everything FFTW needs to plan that size's r2c, c2r and complex transforms.
struct SizeWisdom {
  int n;
  const char* wisdom;
};

// Generated at build time (engine/CMakeLists.txt, wisdom_gen/fftw_wisdom_gen.cc); a single
// {0, ""} without.
constexpr SizeWisdom kBuiltinWisdom[] = {
#include "engine/tdoa/fftw_builtin_wisdom.inc"
};
constexpr std::size_t kBuiltinSizes = std::size(kBuiltinWisdom);

// Which sizes' wisdom has been imported (or is not to be: after ForgetFftwWisdom).
// GUARDED_BY(FftwPlannerMutex())
std::array<bool, kBuiltinSizes>& Imported() {
  static std::array<bool, kBuiltinSizes> imported{};
  return imported;
}

// The planner mutex must be held. False when FFTW refused the entry or it is empty.
bool ImportEntryLocked(std::size_t k) {
  Imported()[k] = true;
  const SizeWisdom& entry = kBuiltinWisdom[k];
  return entry.wisdom[0] != '\0' && fftwf_import_wisdom_from_string(entry.wisdom) != 0;
}

// The entry for size n, or kBuiltinSizes when the table has none.
std::size_t EntryOf(int n) {
  std::size_t k = 0;
  while (k < kBuiltinSizes && kBuiltinWisdom[k].n != n) ++k;
  return k;
}

// Before size n's first plan; the planner mutex must be held.
void ImportSizeOnceLocked(int n) {
  const std::size_t k = EntryOf(n);
  if (k < kBuiltinSizes && !Imported()[k]) ImportEntryLocked(k);
}

}  // namespace

bool ImportBuiltinFftwWisdom() {
  std::lock_guard<std::mutex> lock(FftwPlannerMutex());
  bool all = true;
  for (std::size_t k = 0; k < kBuiltinSizes; ++k) all = ImportEntryLocked(k) && all;
  return all;
}

bool ImportBuiltinFftwWisdom(int n) {
  std::lock_guard<std::mutex> lock(FftwPlannerMutex());
  const std::size_t k = EntryOf(n);
  return k < kBuiltinSizes && ImportEntryLocked(k);
}

void ForgetFftwWisdom() {
  std::lock_guard<std::mutex> lock(FftwPlannerMutex());
  fftwf_forget_wisdom();
  Imported().fill(true);
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
  ImportSizeOnceLocked(n);
  return FftwPlan(fftwf_plan_dft_r2c_1d(n, in, AsComplex(out_interleaved), flags));
}

FftwPlan PlanRealInverse(int n, float* in_interleaved, float* out, unsigned flags) {
  std::lock_guard<std::mutex> lock(FftwPlannerMutex());
  ImportSizeOnceLocked(n);
  return FftwPlan(fftwf_plan_dft_c2r_1d(n, AsComplex(in_interleaved), out, flags));
}

FftwPlan PlanComplex(int n, float* in_interleaved, float* out_interleaved, int sign, unsigned flags) {
  std::lock_guard<std::mutex> lock(FftwPlannerMutex());
  ImportSizeOnceLocked(n);
  return FftwPlan(fftwf_plan_dft_1d(n, AsComplex(in_interleaved), AsComplex(out_interleaved), sign, flags));
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
