// AllFinite (engine/core/finite.h) against std::isfinite on every class of float.
#include "engine/core/finite.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>
#include <vector>

namespace localizer::engine {
namespace {

TEST(AllFinite, AgreesWithIsfiniteOnEveryClassOfValue) {
  using L = std::numeric_limits<float>;
  const std::vector<float> finite = {
      0.0f, -0.0f, 1.0f, -1.0f, L::max(), L::lowest(), L::min(), L::denorm_min(), -L::denorm_min(), 1e-30f, 3.4e38f};
  const std::vector<float> non_finite = {L::infinity(), -L::infinity(), L::quiet_NaN(), -L::quiet_NaN(),
                                         L::signaling_NaN()};
  EXPECT_TRUE(AllFinite(finite.data(), static_cast<int64_t>(finite.size())));
  for (float bad : non_finite) {
    ASSERT_FALSE(std::isfinite(bad));
    // At every position of a block long enough to take the vectorised path and its tail.
    std::mt19937 rng(7);
    std::normal_distribution<float> normal;
    std::vector<float> block(1027);
    for (float& v : block) v = normal(rng);
    ASSERT_TRUE(AllFinite(block.data(), static_cast<int64_t>(block.size())));
    for (size_t at : {size_t{0}, size_t{1}, size_t{15}, size_t{16}, size_t{511}, size_t{1026}}) {
      const float kept = block[at];
      block[at] = bad;
      EXPECT_FALSE(AllFinite(block.data(), static_cast<int64_t>(block.size()))) << bad << " at " << at;
      block[at] = kept;
    }
  }
  EXPECT_TRUE(AllFinite(nullptr, 0));
}

}  // namespace
}  // namespace localizer::engine
