// The batched initialisation's launch plan on the host (gpu/filters/init_builder.h): the
// parameters each slot gets (relative to its array's centroid, rounded to float, its seed and
// Philox window), what is refused, and the grid: every particle of every slot is served by
// exactly one (block, thread) of the launch, which knows its slot and its index in it, as
// InitialiseBatchKernel computes them. ParticleBank::Initialise's device equality with the
// one-slot calls is particle_bank_init_test.cc's.
//
// gpu/filters is compiled only in CUDA builds (gpu/CMakeLists.txt); elsewhere this test
// reports itself skipped.
#if defined(LOCALIZER_HAVE_CUDA)

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <vector>

#include "gpu/filters/init_builder.h"
#include "gpu/filters/slot_layout.h"
#include "tests/gpu/pf_test_scenarios.h"

namespace localizer::gpu::pf {
namespace {

using testing::CvOptions;
using testing::Tetrahedron;

SessionConfig Config(const engine::Vec3& centre, uint64_t seed) {
  auto config = MakeSessionConfig(Tetrahedron(2.0, centre, 1500.0), CvOptions(1000, seed));
  EXPECT_TRUE(config.ok()) << config.status().ToString();
  return *config;
}

TEST(PfInitBuilder, GaussianParametersAreRelativeToTheCentroidInFloat) {
  const SessionConfig config = Config(engine::Vec3(100.0, -20.0, 3.0), 77);
  engine::Vec6 mean;
  mean << 101.5, -18.0, 2.0, 0.5, -1.0, 0.25;
  engine::Mat6 root = engine::Mat6::Zero();
  for (int r = 0; r < 6; ++r) {
    for (int c = 0; c <= r; ++c) root(r, c) = 0.1 * (r + 1) + 0.01 * c;
  }
  GaussianInit init{};
  ASSERT_TRUE(MakeGaussianInit(config, mean, root, 5, &init).ok());
  for (int r = 0; r < 6; ++r) {
    const double origin = r < 3 ? config.origin_m[r] : 0.0;
    EXPECT_EQ(init.mean[r], static_cast<float>(mean(r) - origin)) << r;
    for (int c = 0; c < 6; ++c) EXPECT_EQ(init.root[r * 6 + c], static_cast<float>(root(r, c)));
  }
  EXPECT_NEAR(init.mean[0], 1.5f, 1e-5f);  // the centroid of a tetrahedron about its centre
  EXPECT_EQ(init.seed, 77u);
  EXPECT_EQ(init.draw, 5u);
  mean(4) = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(MakeGaussianInit(config, mean, root, 6, &init).code(), StatusCode::kInvalidArgument);
  mean(4) = 0.0;
  root(2, 1) = std::numeric_limits<double>::infinity();
  EXPECT_EQ(MakeGaussianInit(config, mean, root, 6, &init).code(), StatusCode::kInvalidArgument);
  EXPECT_EQ(init.draw, 5u);  // refused: untouched
}

TEST(PfInitBuilder, RegionParametersAndWhatIsRefused) {
  const SessionConfig config = Config(engine::Vec3(-5.0, 0.0, 40.0), 3);
  RegionInit init{};
  const engine::Vec3 lo(-8.0, -2.0, 38.0), hi(-4.0, 6.0, 38.0);  // a flat box is fine
  ASSERT_TRUE(MakeRegionInit(config, lo, hi, 0.7, 9, &init).ok());
  for (int a = 0; a < 3; ++a) {
    EXPECT_EQ(init.lo[a], static_cast<float>(lo(a) - config.origin_m[a])) << a;
    EXPECT_EQ(init.span[a], static_cast<float>(hi(a) - lo(a))) << a;
  }
  EXPECT_EQ(init.speed_sigma, 0.7f);
  EXPECT_EQ(init.seed, 3u);
  EXPECT_EQ(init.draw, 9u);
  EXPECT_EQ(MakeRegionInit(config, hi, lo, 0.7, 10, &init).code(), StatusCode::kInvalidArgument);   // min > max
  EXPECT_EQ(MakeRegionInit(config, lo, hi, -0.1, 10, &init).code(), StatusCode::kInvalidArgument);  // speed < 0
  EXPECT_EQ(MakeRegionInit(config, lo, hi, std::numeric_limits<double>::infinity(), 10, &init).code(),
            StatusCode::kInvalidArgument);
  const engine::Vec3 nan(0.0, std::numeric_limits<double>::quiet_NaN(), 0.0);
  EXPECT_EQ(MakeRegionInit(config, nan, hi, 0.7, 10, &init).code(), StatusCode::kInvalidArgument);
  EXPECT_EQ(init.draw, 9u);
}

// Slots of many sizes (a partial last block, exactly one block, many blocks, one particle):
// walking the grid as the kernel does covers each slot's particles once, in its own task.
TEST(PfInitBuilder, EveryParticleOfEverySlotIsServedOnceByItsOwnTask) {
  const std::vector<int> particles = {1000, 256, 1, 70000, 257, 4096, 255};
  InitPlan plan;
  std::vector<std::vector<int>> served;
  for (std::size_t k = 0; k < particles.size(); ++k) {
    const SlotLayout layout = SlotLayout::For(particles[k]);
    InitTask task;
    task.slot.particles = layout.particles;
    task.slot.blocks = layout.blocks;
    task.kind = k % 2 == 0 ? kInitGaussian : kInitRegion;
    task.gaussian.draw = task.region.draw = 100 + k;  // a marker to find the task by
    plan.Add(task);
    served.emplace_back(particles[k], 0);
  }
  ASSERT_EQ(plan.tasks.size(), particles.size());
  int expected_blocks = 0;
  for (int n : particles) expected_blocks += (n + kBlockThreads - 1) / kBlockThreads;
  ASSERT_EQ(plan.blocks(), expected_blocks);
  for (int block = 0; block < plan.blocks(); ++block) {
    const int k = plan.block_task[static_cast<std::size_t>(block)];
    const InitTask& t = plan.tasks[static_cast<std::size_t>(k)];
    ASSERT_EQ(t.kind == kInitGaussian ? t.gaussian.draw : t.region.draw, 100u + k);
    for (int thread = 0; thread < kBlockThreads; ++thread) {
      const int i = (block - t.first_block) * kBlockThreads + thread;
      ASSERT_GE(i, 0);
      if (i < t.slot.particles) ++served[static_cast<std::size_t>(k)][static_cast<std::size_t>(i)];
    }
  }
  for (std::size_t k = 0; k < particles.size(); ++k) {
    for (int count : served[k]) ASSERT_EQ(count, 1) << "slot " << k;
  }
  plan.Clear();
  EXPECT_EQ(plan.blocks(), 0);
  EXPECT_TRUE(plan.tasks.empty());
}

}  // namespace
}  // namespace localizer::gpu::pf

#else

#include <gtest/gtest.h>

TEST(PfInitBuilder, NeedsTheCudaBuild) { GTEST_SKIP() << "built without CUDA: gpu/filters is not compiled"; }

#endif
