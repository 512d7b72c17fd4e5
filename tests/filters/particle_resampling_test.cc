// ParticleSet's resampling (engine/filters/particle_resampling.cc, particle_modes.cc): every
// resampled slot sits on the parent resample_index() names, moved only by the kernel, on the
// vectorised paths (parents read by loads and a permute, or by a gather) and the scalar
// remainder; and while several labels live, each label is moved with its own kernel.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <vector>

#include "engine/filters/particle_filter.h"
#include "engine/filters/particle_gather.h"
#include "engine/filters/particle_set.h"
#include "tests/filters/tdoa_frames.h"

namespace localizer::engine {
namespace {

// As particle_filter_test's options: a quiet motion model and 8 us TDOAs, seeded.
ParticleFilterOptions Options() {
  ParticleFilterOptions o;
  o.particles = 4096;
  o.accel_noise_mps2 = 0.05;
  o.tdoa_sigma_s = 8e-6;
  o.likelihood = Likelihood::kPeak;
  o.seed = 42;
  return o;
}

TEST(ParticleFilter, ResamplingGivesEverySlotItsParentMovedOnlyByTheKernel) {
  // Particles spread over a 10 m box; weights (through TakeParticles' log-weights) either
  // concentrated on a run of neighbours (a block of 16 slots draws from a few consecutive
  // particles: the vectorised path's loads and permute) or on every 37th particle (parents
  // too far apart for that: its gather). With a tiny kernel each slot must sit on the
  // particle resample_index() names; a wrong lane or offset lands metres away. Particle
  // counts with and without a remainder of 16.
  const ArrayGeometry array = Tetrahedron(2.0, Vec3::Zero(), 343.0);
  for (int n : {4096, 4099, 45}) {
    ParticleFilterOptions o = Options();
    o.particles = n;
    ParticleSet spread(array, o);
    spread.SampleUniformBox(Vec3(-5.0, -5.0, -5.0), Vec3(5.0, 5.0, 5.0), 1.0);
    for (const bool sparse : {false, true}) {
      std::vector<float> log_weights(static_cast<size_t>(n));
      for (int i = 0; i < n; ++i) {
        const double u = (i - 0.4 * n) / (0.05 * n + 1.0);
        log_weights[static_cast<size_t>(i)] = sparse ? (i % 37 == 0 ? 0.0f : -80.0f) : static_cast<float>(-0.5 * u * u);
      }
      ParticleSet set(array, o);
      set.TakeParticles({&spread}, std::vector<uint8_t>(static_cast<size_t>(n), 0), log_weights);
      std::array<std::vector<float>, 6> before;
      for (size_t r = 0; r < 6; ++r) before[r].assign(set.columns()[r], set.columns()[r] + n);
      set.ResampleSystematic(1e-4);
      const AlignedVector<int>& parent = set.resample_index();
      int distinct = 1;
      for (int m = 0; m < n; ++m) {
        const int j = parent[static_cast<size_t>(m)];
        ASSERT_TRUE(j >= 0 && j < n) << "slot " << m;
        if (m > 0) {
          ASSERT_GE(j, parent[static_cast<size_t>(m - 1)]) << "systematic resampling keeps the order";
          distinct += j != parent[static_cast<size_t>(m - 1)];
        }
        if (sparse) {
          ASSERT_EQ(j % 37, 0) << "slot " << m << " copied a particle of no weight";
        }
        double moved2 = 0.0;
        for (size_t r = 0; r < 3; ++r) {
          const double d = set.columns()[r][m] - before[r][static_cast<size_t>(j)];
          moved2 += d * d;
        }
        ASSERT_LT(std::sqrt(moved2), 0.01) << "n " << n << (sparse ? " sparse" : " concentrated") << ", slot " << m;
      }
      std::printf("n %d, %s weights: %d distinct parents\n", n, sparse ? "sparse" : "concentrated", distinct);
    }
  }
}

TEST(ParticleFilter, ResamplingSeveralLabelsMovesEachWithItsOwnKernel) {
  // Five hypotheses 20 m apart, each with its own spread (5 to 25 cm), equal weights. The
  // per-label kernel move (Liu & West with each label's own mean and covariance) keeps every
  // label's mean and spread; a slot given another label's root or shift (a wrong lane of the
  // vectorised path) would land with a spread up to 5 times off, or metres away. A wide
  // kernel (h = 0.88: 78 % of each label's variance is the kernel's draw after the move) so
  // that a wrong root shows. Particle counts with and without a remainder of 16.
  const ArrayGeometry array = Tetrahedron(2.0, Vec3::Zero(), 343.0);
  for (int n : {16384, 16387}) {
    ParticleFilterOptions o = Options();
    o.particles = n;
    ParticleSet set(array, o);
    std::vector<ParticleSet::Component> components;
    for (int c = 0; c < 5; ++c) {
      ParticleSet::Component component;
      component.mean.head<3>() = Vec3(20.0 * c, 5.0, -3.0);
      component.root = Mat6::Identity() * 0.05 * (c + 1);
      components.push_back(component);
    }
    set.SampleMixture(components);
    ASSERT_EQ(set.labels(), 5);
    set.ResampleSystematic(2.5);
    ASSERT_EQ(set.labels(), 5);
    const std::vector<WeightedBelief> modes = set.Modes(0.0);
    ASSERT_EQ(modes.size(), 5u);
    for (const WeightedBelief& mode : modes) {
      const int c = static_cast<int>(std::lround(mode.belief.mean.x() / 20.0));
      ASSERT_TRUE(c >= 0 && c < 5) << mode.belief.mean.transpose();
      const double sd = 0.05 * (c + 1);
      // ~3300 particles per label: the mean within a few standard errors, the spread within 10 %
      // (label 0's root in every lane would leave label 4's spread 50 % short).
      EXPECT_LT((mode.belief.mean.head<3>() - components[static_cast<size_t>(c)].mean.head<3>()).norm(), 0.5 * sd)
          << "n " << n << ", label at x = " << 20 * c;
      for (int axis = 0; axis < 6; ++axis) {
        EXPECT_NEAR(std::sqrt(mode.belief.covariance(axis, axis)), sd, 0.1 * sd)
            << "n " << n << ", label at x = " << 20 * c << ", axis " << axis;
      }
    }
  }
}

TEST(ParticleSet, GatherSortedCarriesEachSlotsParentsValue) {
  // The per-particle values resampling carries (levels, turn rates, speed changes): runs of
  // neighbours (the loads-and-permute path), jumps of 40 particles (the gather path), a
  // parent at the array's last entry, and counts with and without a remainder of 16.
  for (int n : {4096, 4099, 45, 16, 3}) {
    std::vector<float> value(static_cast<size_t>(n));
    for (int i = 0; i < n; ++i) value[static_cast<size_t>(i)] = 0.5f + static_cast<float>(i);
    // Parents advance by 0 or 1 per slot in even blocks of 64 slots, by 40 in odd ones, and
    // stop at the last particle.
    std::vector<int> index(static_cast<size_t>(n));
    int parent = 0;
    for (int m = 0; m < n; ++m) {
      parent = std::min(n - 1, parent + ((m / 64) % 2 == 0 ? m % 2 : 40));
      index[static_cast<size_t>(m)] = parent;
    }
    std::vector<float> carried(static_cast<size_t>(n), -1.0f);
    GatherSorted(value.data(), index.data(), n, carried.data());
    for (int m = 0; m < n; ++m) {
      ASSERT_EQ(carried[static_cast<size_t>(m)], value[static_cast<size_t>(index[static_cast<size_t>(m)])])
          << "n " << n << ", slot " << m;
    }
  }
}

}  // namespace
}  // namespace localizer::engine
