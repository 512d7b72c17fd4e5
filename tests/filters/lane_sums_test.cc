// LaneSums (engine/filters/lane_sums.h): the fixed-lane order the particle filter's sums keep
// whatever vector width particle_set.cc is compiled for.
#include "engine/filters/lane_sums.h"

#include <gtest/gtest.h>

#include <cstring>
#include <random>
#include <vector>

namespace localizer::engine {
namespace {

// The order spelled out one term at a time: lane i mod 8 over the whole blocks, the rest in
// lane 0, then ((init + lane 0) + lane 1) + ... + lane 7.
float ReferenceSum(const std::vector<float>& v, float init) {
  float lane[8] = {};
  const size_t whole = v.size() / 8 * 8;
  for (size_t i = 0; i < whole; ++i) lane[i % 8] += v[i];
  for (size_t i = whole; i < v.size(); ++i) lane[0] += v[i];
  float s = init;
  for (const float l : lane) s += l;
  return s;
}

TEST(LaneSums, KeepsTheEightLaneOrderForEveryLength) {
  std::mt19937 rng(5);
  std::normal_distribution<float> normal;
  for (int n = 0; n < 70; ++n) {
    std::vector<float> v(static_cast<size_t>(n));
    for (float& x : v) x = normal(rng) * 1e3f;
    float got[1];
    LaneSums<float, 1>(
        0, n, {0.5f}, [&](int i, int lane, float(*acc)[kSumLanes<float>]) { acc[0][lane] += v[i]; }, got);
    const float want = ReferenceSum(v, 0.5f);
    EXPECT_EQ(0, std::memcmp(&got[0], &want, sizeof want)) << "n = " << n << ": " << got[0] << " vs " << want;
  }
}

TEST(LaneSums, CountsLanesFromTheFirstIndexAndKeepsSeveralSumsApart) {
  std::vector<double> v(37);
  for (size_t i = 0; i < v.size(); ++i) v[i] = 1.0 / static_cast<double>(i + 1);
  double got[2];
  LaneSums<double, 2>(
      5, 36, {0.0, 1.0},
      [&](int i, int lane, double(*acc)[kSumLanes<double>]) {
        acc[0][lane] += v[i];
        acc[1][lane] += 2.0 * v[i];
      },
      got);
  // Four lanes for double: terms 5 .. 32 in whole blocks of 4 from index 5, 33 .. 35 in lane 0.
  double lane[4] = {};
  for (int i = 5; i < 33; ++i) lane[(i - 5) % 4] += v[i];
  for (int i = 33; i < 36; ++i) lane[0] += v[i];
  const double want = ((lane[0] + lane[1]) + lane[2]) + lane[3];
  EXPECT_EQ(got[0], 0.0 + want);
  EXPECT_DOUBLE_EQ(got[1], 1.0 + 2.0 * want);
}

}  // namespace
}  // namespace localizer::engine
