// Batched (re)initialisation on a device (ParticleBank::Initialise): sessions initialised in
// one launch get, bit for bit, what each gets from the one-slot calls (InitialiseGaussian /
// InitialiseRegion, then Moments), and keep stepping alike; bad requests get their own status
// while the others run. Every test skips (with the reason) where no GPU can be used; the
// launch plan and the per-particle maths are tested on the host (pf_init_builder_test.cc,
// pf_math_test.cu).
//
// gpu/filters is compiled only in CUDA builds (gpu/CMakeLists.txt); elsewhere this test
// reports itself skipped.
#if defined(LOCALIZER_HAVE_CUDA)

#include <gtest/gtest.h>

#include <limits>
#include <memory>
#include <random>
#include <vector>

#include "gpu/filters/particle_bank.h"
#include "tests/gpu/gpu_test_util.h"
#include "tests/gpu/pf_test_scenarios.h"

namespace localizer::gpu {
namespace {

using testing::CovarianceRoot;
using testing::CvOptions;
using testing::CvScenario;
using testing::MakeMeasurement;

std::unique_ptr<ParticleBank> NewBank() {
  auto bank = ParticleBank::Create(0);
  EXPECT_TRUE(bank.ok()) << bank.status().ToString();
  return bank.ok() ? std::move(bank).value() : nullptr;
}

// Sessions of several sizes and seeds, Gaussian and region starts mixed.
struct Start {
  engine::ParticleFilterOptions options;
  ParticleBank::InitRequest request;  // slot filled in per bank
};

std::vector<Start> Starts(const CvScenario& s) {
  const engine::TrackState belief = s.Belief();
  std::vector<Start> starts;
  const int sizes[] = {4096, 1000, 300, 70000, 257};
  for (int k = 0; k < 5; ++k) {
    Start start{CvOptions(sizes[k], 10 + k), {}};
    if (k % 2 == 0) {
      start.request.mean = belief.mean;
      start.request.mean(0) += k;  // each its own belief
      start.request.root = CovarianceRoot(belief.covariance);
    } else {
      start.request.region = true;
      start.request.min_m = s.p0 - engine::Vec3(2.0 + k, 2.0, 1.0);
      start.request.max_m = s.p0 + engine::Vec3(2.0, 3.0, 1.0 + k);
      start.request.speed_sigma_mps = 0.5 * k;
    }
    starts.push_back(start);
  }
  return starts;
}

Status InitialiseOneByOne(ParticleBank& bank, int slot, const ParticleBank::InitRequest& r) {
  return r.region ? bank.InitialiseRegion(slot, r.min_m, r.max_m, r.speed_sigma_mps)
                  : bank.InitialiseGaussian(slot, r.mean, r.root);
}

// One predict-and-update step of every slot, together.
std::vector<ParticleBank::StepResult> StepAll(ParticleBank& bank, const CvScenario& s, const std::vector<int>& slots) {
  std::mt19937_64 rng(8);
  const engine::Measurement m = MakeMeasurement(s.array, s.p0, s.v, s.hop_s, s.sigma_s, s.fs, rng);
  const std::vector<int> used(m.pairs.size(), 1);
  const std::vector<double> sigmas(m.pairs.size(), 8e-6);
  std::vector<ParticleBank::StepRequest> requests;
  for (int slot : slots) requests.push_back({slot, s.hop_s, &m, used.data(), sigmas.data()});
  std::vector<ParticleBank::StepResult> results(requests.size());
  EXPECT_TRUE(bank.Step(requests, results).ok());
  return results;
}

void ExpectSameState(const engine::TrackState& a, const engine::TrackState& b) {
  EXPECT_EQ(a.mean, b.mean);
  EXPECT_EQ(a.covariance, b.covariance);
}

TEST(ParticleBankInit, OneLaunchGivesWhatOneByOneGivesBitForBit) {
  LOCALIZER_SKIP_WITHOUT_GPU();
  const CvScenario s;
  const std::vector<Start> starts = Starts(s);
  auto alone = NewBank(), together = NewBank();
  ASSERT_TRUE(alone && together);
  std::vector<int> slots_alone, slots_together;
  for (const Start& start : starts) {
    slots_alone.push_back(*alone->Open(s.array, start.options));
    slots_together.push_back(*together->Open(s.array, start.options));
  }
  // Twice: a start, then a restart (the slots' Philox windows have moved on, alike).
  for (int round = 0; round < 2; ++round) {
    SCOPED_TRACE("round " + std::to_string(round));
    std::vector<engine::TrackState> expected;
    for (std::size_t k = 0; k < starts.size(); ++k) {
      ASSERT_TRUE(InitialiseOneByOne(*alone, slots_alone[k], starts[k].request).ok());
      auto moments = alone->Moments(slots_alone[k]);
      ASSERT_TRUE(moments.ok()) << moments.status().ToString();
      expected.push_back(*moments);
    }
    std::vector<ParticleBank::InitRequest> requests;
    for (std::size_t k = 0; k < starts.size(); ++k) {
      requests.push_back(starts[k].request);
      requests.back().slot = slots_together[k];
    }
    std::vector<ParticleBank::InitResult> results(requests.size());
    ASSERT_TRUE(together->Initialise(requests, results).ok());
    for (std::size_t k = 0; k < starts.size(); ++k) {
      SCOPED_TRACE("session " + std::to_string(k));
      ASSERT_TRUE(results[k].status.ok()) << results[k].status.ToString();
      ExpectSameState(results[k].state, expected[k]);
    }
    // The particles themselves, not only their moments: the next step agrees too.
    const auto stepped_alone = StepAll(*alone, s, slots_alone);
    const auto stepped_together = StepAll(*together, s, slots_together);
    for (std::size_t k = 0; k < starts.size(); ++k) {
      SCOPED_TRACE("session " + std::to_string(k));
      ASSERT_TRUE(stepped_alone[k].status.ok() && stepped_together[k].status.ok());
      ExpectSameState(stepped_alone[k].state, stepped_together[k].state);
      EXPECT_EQ(stepped_alone[k].ess, stepped_together[k].ess);
      EXPECT_EQ(stepped_alone[k].resampled, stepped_together[k].resampled);
    }
  }
}

TEST(ParticleBankInit, BadRequestsGetTheirOwnStatusAndTheOthersRun) {
  LOCALIZER_SKIP_WITHOUT_GPU();
  const CvScenario s;
  auto bank = NewBank();
  ASSERT_TRUE(bank);
  const int a = *bank->Open(s.array, CvOptions(1000, 1)), b = *bank->Open(s.array, CvOptions(1000, 2));
  const std::vector<Start> starts = Starts(s);
  std::vector<ParticleBank::InitRequest> requests(5, starts[0].request);
  requests[0].slot = a;
  requests[1].slot = 99;  // not open
  requests[2].slot = a;   // twice
  requests[3].slot = b;
  requests[3].mean(2) = std::numeric_limits<double>::quiet_NaN();
  requests[4] = starts[1].request;
  requests[4].slot = b;
  std::vector<ParticleBank::InitResult> results(requests.size());
  ASSERT_TRUE(bank->Initialise(requests, results).ok());
  EXPECT_TRUE(results[0].status.ok()) << results[0].status.ToString();
  EXPECT_EQ(results[1].status.code(), StatusCode::kInvalidArgument);
  EXPECT_EQ(results[2].status.code(), StatusCode::kInvalidArgument);
  EXPECT_EQ(results[3].status.code(), StatusCode::kInvalidArgument);
  EXPECT_TRUE(results[4].status.ok()) << results[4].status.ToString();
  auto moments = bank->Moments(b);  // initialised by the region request
  ASSERT_TRUE(moments.ok());
  ExpectSameState(*moments, results[4].state);
  std::vector<ParticleBank::InitResult> too_few(1);
  EXPECT_EQ(bank->Initialise(requests, too_few).code(), StatusCode::kInvalidArgument);
}

}  // namespace
}  // namespace localizer::gpu

#else

#include <gtest/gtest.h>

TEST(ParticleBankInit, NeedsTheCudaBuild) { GTEST_SKIP() << "built without CUDA: gpu/filters is not compiled"; }

#endif
