// The built-in FFTW wisdom (engine/tdoa/fftw_util.h) changes how long planning takes, never
// which plan is made: for every size it covers, a plan made from that size's entry alone is
// the plan FFTW_ESTIMATE makes without any wisdom (compared as fftwf_sprint_plan's text), so
// estimates do not move; and the entry does cover the problems the engine plans
// (FFTW_WISDOM_ONLY finds a plan).
#include <fftw3.h>
#include <gtest/gtest.h>

#include <cstdlib>
#include <string>
#include <vector>

#include "engine/tdoa/fftw_util.h"

namespace localizer::engine {
namespace {

// fftwf_sprint_plan's description of a plan, "" for none.
std::string Describe(const FftwPlan& plan) {
  if (!plan) return "";
  char* text = fftwf_sprint_plan(plan.get());
  std::string out = text != nullptr ? text : "";
  std::free(text);
  return out;
}

struct Plans {
  std::string forward, inverse, packed_forward, packed_inverse;
};

// Forgets all wisdom, then (with_wisdom) imports size n's built-in entry alone, and plans
// size n as the engine does (fftwf_malloc'd arrays, out of place, FFTW_ESTIMATE).
Plans PlanFresh(int n, bool with_wisdom) {
  ForgetFftwWisdom();
  if (with_wisdom) {
    EXPECT_TRUE(ImportBuiltinFftwWisdom(n)) << n;
  }
  FftwFloats real = AllocateFftwFloats(n);
  FftwFloats complex = AllocateFftwFloats(2 * (n / 2 + 1));
  FftwFloats packed_in = AllocateFftwFloats(2 * n);
  FftwFloats packed_out = AllocateFftwFloats(2 * n);
  return {Describe(PlanRealForward(n, real.get(), complex.get(), FFTW_ESTIMATE)),
          Describe(PlanRealInverse(n, complex.get(), real.get(), FFTW_ESTIMATE)),
          Describe(PlanComplex(n, packed_in.get(), packed_out.get(), FFTW_FORWARD, FFTW_ESTIMATE)),
          Describe(PlanComplex(n, packed_in.get(), packed_out.get(), FFTW_BACKWARD, FFTW_ESTIMATE))};
}

std::vector<int> CoveredSizes() {
  std::vector<int> sizes;
  for (int base : {1, 3, 5}) {
    int n = base;
    while (n < 64) n *= 2;
    for (; n <= (1 << 16); n *= 2) sizes.push_back(n);  // the frames sessions use; 2^17..2^21 take long to plan
  }
  return sizes;
}

TEST(BuiltinFftwWisdom, GivesThePlansEstimateMakesWithoutIt) {
  if (!ImportBuiltinFftwWisdom()) GTEST_SKIP() << "built without LOCALIZER_FFTW_WISDOM (or FFTW refused it)";
  for (int n : CoveredSizes()) {
    const Plans estimated = PlanFresh(n, /*with_wisdom=*/false);
    const Plans from_wisdom = PlanFresh(n, /*with_wisdom=*/true);
    ASSERT_FALSE(estimated.forward.empty()) << n;
    EXPECT_EQ(from_wisdom.forward, estimated.forward) << "r2c of size " << n;
    EXPECT_EQ(from_wisdom.inverse, estimated.inverse) << "c2r of size " << n;
    EXPECT_EQ(from_wisdom.packed_forward, estimated.packed_forward) << "forward c2c of size " << n;
    EXPECT_EQ(from_wisdom.packed_inverse, estimated.packed_inverse) << "backward c2c of size " << n;
    // The size's entry alone plans it: the engine's problems (alignment, out of place) are
    // the covered ones.
    ForgetFftwWisdom();
    ASSERT_TRUE(ImportBuiltinFftwWisdom(n)) << n;
    FftwFloats real = AllocateFftwFloats(n);
    FftwFloats complex = AllocateFftwFloats(2 * (n / 2 + 1));
    EXPECT_TRUE(PlanRealForward(n, real.get(), complex.get(), FFTW_ESTIMATE | FFTW_WISDOM_ONLY)) << n;
    EXPECT_TRUE(PlanRealInverse(n, complex.get(), real.get(), FFTW_ESTIMATE | FFTW_WISDOM_ONLY)) << n;
    FftwFloats packed_in = AllocateFftwFloats(2 * n);
    FftwFloats packed_out = AllocateFftwFloats(2 * n);
    for (int sign : {FFTW_FORWARD, FFTW_BACKWARD}) {
      EXPECT_TRUE(PlanComplex(n, packed_in.get(), packed_out.get(), sign, FFTW_ESTIMATE | FFTW_WISDOM_ONLY)) << n;
    }
  }
  ImportBuiltinFftwWisdom();  // leave the process as the engine would
}

TEST(BuiltinFftwWisdom, ASizeItDoesNotCoverIsStillPlanned) {
  const int n = 7 * 64;  // NextFastFftSize never returns it
  EXPECT_FALSE(ImportBuiltinFftwWisdom(n));
  EXPECT_FALSE(PlanFresh(n, /*with_wisdom=*/false).forward.empty());
  EXPECT_EQ(NextFastFftSize(n), 512);
  ImportBuiltinFftwWisdom();
}

// Without the built-in wisdom FFTW_WISDOM_ONLY plans nothing, so the test above is not
// vacuous: ForgetFftwWisdom leaves no wisdom and stops the lazy import.
TEST(BuiltinFftwWisdom, ForgettingLeavesNothingToPlanFrom) {
  if (!ImportBuiltinFftwWisdom()) GTEST_SKIP() << "built without LOCALIZER_FFTW_WISDOM (or FFTW refused it)";
  ForgetFftwWisdom();
  FftwFloats real = AllocateFftwFloats(4096);
  FftwFloats complex = AllocateFftwFloats(2 * (4096 / 2 + 1));
  EXPECT_FALSE(PlanRealForward(4096, real.get(), complex.get(), FFTW_ESTIMATE | FFTW_WISDOM_ONLY));
  ImportBuiltinFftwWisdom();
  EXPECT_TRUE(PlanRealForward(4096, real.get(), complex.get(), FFTW_ESTIMATE | FFTW_WISDOM_ONLY));
}

}  // namespace
}  // namespace localizer::engine
