// The particle bank on a device: replay, batching invariance, convergence, accuracy against
// the CPU filter, memory accounting and the per-request contract. Every test skips (with
// the reason) where no GPU can be used; the maths they rely on is tested on the host in
// pf_math_test.cu, pf_step_builder_test.cc and pf_host_model_test.cc.
//
// gpu/filters is compiled only in CUDA builds (gpu/CMakeLists.txt); elsewhere this test
// reports itself skipped.
#if defined(LOCALIZER_HAVE_CUDA)

#include "gpu/filters/particle_bank.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <memory>
#include <random>
#include <vector>

#include "gpu/core/device.h"
#include "gpu/filters/slot_layout.h"
#include "tests/gpu/gpu_test_util.h"
#include "tests/gpu/pf_test_scenarios.h"

namespace localizer::gpu {
namespace {

using testing::CovarianceRoot;
using testing::CvOptions;
using testing::CvScenario;
using testing::MakeMeasurement;
using testing::Tetrahedron;
using testing::WellConditionedScenario;

std::unique_ptr<ParticleBank> NewBank(std::size_t limit = 0) {
  auto bank = ParticleBank::Create(limit);
  EXPECT_TRUE(bank.ok()) << bank.status().ToString();
  return bank.ok() ? std::move(bank).value() : nullptr;
}

int OpenInitialised(ParticleBank& bank, const CvScenario& s, const engine::ParticleFilterOptions& o) {
  auto slot = bank.Open(s.array, o);
  EXPECT_TRUE(slot.ok()) << slot.status().ToString();
  if (!slot.ok()) return -1;
  const engine::TrackState belief = s.Belief();
  EXPECT_TRUE(bank.InitialiseGaussian(*slot, belief.mean, CovarianceRoot(belief.covariance)).ok());
  return *slot;
}

// One session's inputs for a frame: the measurement and the arrays the request points to.
struct Frame {
  engine::Measurement m;
  std::vector<int> used;
  std::vector<double> sigmas;
  ParticleBank::StepRequest Request(int slot, double dt_s) const {
    return {slot, dt_s, &m, used.data(), sigmas.data()};
  }
};

Frame MakeFrame(const CvScenario& s, double t_s, std::mt19937_64& rng) {
  Frame f;
  f.m = MakeMeasurement(s.array, s.p0, s.v, t_s, s.sigma_s, s.fs, rng);
  f.used.assign(f.m.pairs.size(), 1);
  f.sigmas.assign(f.m.pairs.size(), 8e-6);
  return f;
}

void ExpectIdentical(const ParticleBank::StepResult& a, const ParticleBank::StepResult& b) {
  ASSERT_TRUE(a.status.ok()) << a.status.ToString();
  ASSERT_TRUE(b.status.ok()) << b.status.ToString();
  EXPECT_EQ(a.state.mean, b.state.mean);
  EXPECT_EQ(a.state.covariance, b.state.covariance);
  EXPECT_EQ(a.ess, b.ess);
  EXPECT_EQ(a.resampled, b.resampled);
  ASSERT_EQ(a.innovations.size(), b.innovations.size());
  for (size_t p = 0; p < a.innovations.size(); ++p) {
    EXPECT_EQ(a.innovations[p].mean_s, b.innovations[p].mean_s);
    EXPECT_EQ(a.innovations[p].predicted_var_s2, b.innovations[p].predicted_var_s2);
  }
}

// Runs `frames` frames of the CPU tests' scenario on one session and returns every result.
std::vector<ParticleBank::StepResult> RunAlone(const engine::ParticleFilterOptions& o, int frames) {
  const CvScenario s;
  auto bank = NewBank();
  const int slot = OpenInitialised(*bank, s, o);
  std::mt19937_64 rng(5);
  std::vector<ParticleBank::StepResult> out;
  for (int f = 0; f < frames; ++f) {
    const Frame frame = MakeFrame(s, f * s.hop_s, rng);
    const ParticleBank::StepRequest request = frame.Request(slot, f > 0 ? s.hop_s : 0.0);
    ParticleBank::StepResult result;
    EXPECT_TRUE(bank->Step({&request, 1}, {&result, 1}).ok());
    out.push_back(std::move(result));
  }
  return out;
}

// Runs everywhere: without a device Create is a FAILED_PRECONDITION naming why, not a crash.
TEST(ParticleBank, CreateFailsCleanlyWithoutADevice) {
  const auto bank = ParticleBank::Create(0);
  if (DeviceUnavailableReason().empty()) {
    EXPECT_TRUE(bank.ok()) << bank.status().ToString();
  } else {
    EXPECT_EQ(bank.status().code(), StatusCode::kFailedPrecondition);
    EXPECT_NE(bank.status().message().find(DeviceUnavailableReason()), std::string::npos);
  }
}

TEST(ParticleBank, SameSeedSameResultsOtherSeedOtherResults) {
  LOCALIZER_SKIP_WITHOUT_GPU();
  const auto a = RunAlone(CvOptions(4096, 42), 30), b = RunAlone(CvOptions(4096, 42), 30);
  const auto c = RunAlone(CvOptions(4096, 43), 30);
  int resampled = 0;
  for (size_t f = 0; f < a.size(); ++f) {
    ExpectIdentical(a[f], b[f]);
    resampled += a[f].resampled;
  }
  EXPECT_GT(resampled, 0);  // the replay covered resampling too
  EXPECT_NE(a.back().state.mean, c.back().state.mean);
}

// Sessions of different sizes, likelihoods and schedules stepped together give bit for bit
// what each gives alone: blocks never mix sessions and reductions are per session.
TEST(ParticleBank, SessionsSteppedTogetherEqualSessionsSteppedAlone) {
  LOCALIZER_SKIP_WITHOUT_GPU();
  const CvScenario s;
  std::vector<engine::ParticleFilterOptions> options = {CvOptions(4096, 1), CvOptions(1000, 2), CvOptions(300, 3),
                                                        CvOptions(70000, 4)};
  options[2].resample_threshold = 1.0;  // resamples every update
  options[3].kernel_scale = 0.0;        // plain bootstrap
  const int sessions = static_cast<int>(options.size()), frames = 12;
  auto together = NewBank();
  std::vector<std::unique_ptr<ParticleBank>> alone;
  std::vector<int> slot_together, slot_alone;
  for (const auto& o : options) {
    slot_together.push_back(OpenInitialised(*together, s, o));
    alone.push_back(NewBank());
    slot_alone.push_back(OpenInitialised(*alone.back(), s, o));
  }
  std::mt19937_64 rng(9);
  for (int f = 0; f < frames; ++f) {
    std::vector<Frame> inputs;
    for (int k = 0; k < sessions; ++k) inputs.push_back(MakeFrame(s, f * s.hop_s, rng));
    std::vector<ParticleBank::StepRequest> requests;
    for (int k = 0; k < sessions; ++k) {
      // Session 1 skips the update every third frame (predict only); session 2 predicts by
      // a different dt. Requests go in reversed order: order must not matter either.
      const int j = sessions - 1 - k;
      ParticleBank::StepRequest r = inputs[j].Request(slot_together[j], f > 0 ? s.hop_s * (j == 2 ? 0.5 : 1.0) : 0.0);
      if (j == 1 && f % 3 == 2) r.measurement = nullptr;
      requests.push_back(r);
    }
    std::vector<ParticleBank::StepResult> results(requests.size());
    ASSERT_TRUE(together->Step(requests, results).ok());
    for (int k = 0; k < sessions; ++k) {
      const int j = sessions - 1 - k;
      ParticleBank::StepRequest r = requests[k];
      r.slot = slot_alone[j];
      ParticleBank::StepResult result;
      ASSERT_TRUE(alone[j]->Step({&r, 1}, {&result, 1}).ok());
      ExpectIdentical(results[k], result);
    }
  }
}

TEST(ParticleBank, StationarySourceWithExactTdoasConverges) {
  LOCALIZER_SKIP_WITHOUT_GPU();
  CvScenario s = WellConditionedScenario();
  s.sigma_s = 0.0;
  auto bank = NewBank();
  const int slot = OpenInitialised(*bank, s, CvOptions(4096, 7));
  std::mt19937_64 rng(1);
  ParticleBank::StepResult result;
  for (int f = 0; f < 40; ++f) {
    const Frame frame = MakeFrame(s, f * s.hop_s, rng);
    const ParticleBank::StepRequest request = frame.Request(slot, f > 0 ? s.hop_s : 0.0);
    ASSERT_TRUE(bank->Step({&request, 1}, {&result, 1}).ok());
    ASSERT_TRUE(result.status.ok()) << result.status.ToString();
    EXPECT_GT(result.ess, 0.0);
    EXPECT_LE(result.ess, 4096.0 * (1 + 1e-9));
    EXPECT_FALSE(result.cholesky_fallback);
  }
  EXPECT_LT((result.state.mean.head<3>() - s.p0).norm(), 0.05) << result.state.mean.transpose();
  const double trace = result.state.covariance.topLeftCorner<3, 3>().trace();
  const double initial_trace = s.Belief().covariance.topLeftCorner<3, 3>().trace();
  EXPECT_LT(trace, 0.01 * initial_trace);
  EXPECT_GT(trace, 0.0);
}

// The brief's accuracy criterion, as in pf_host_model_test.cc, with all 100 runs stepped
// as 100 sessions of one bank.
TEST(ParticleBank, RmseWithinTenPercentOfTheCpuFilter) {
  LOCALIZER_SKIP_WITHOUT_GPU();
  const CvScenario s = WellConditionedScenario();
  const int runs = 100;
  const double cpu = testing::PooledRmse(
      [&](uint64_t seed) { return testing::CpuCvRmse(s, CvOptions(testing::kComparisonParticles, 100 + seed), seed); },
      runs);
  auto bank = NewBank();
  std::vector<int> slots;
  std::vector<std::mt19937_64> rngs;
  for (int k = 0; k < runs; ++k) {
    slots.push_back(OpenInitialised(*bank, s, CvOptions(testing::kComparisonParticles, 101 + k)));
    rngs.emplace_back(k + 1);
  }
  double sum_sq = 0.0;
  int scored = 0;
  for (int f = 0; f < s.frames; ++f) {
    const double t = f * s.hop_s;
    std::vector<Frame> frames;
    std::vector<ParticleBank::StepRequest> requests;
    for (int k = 0; k < runs; ++k) frames.push_back(MakeFrame(s, t, rngs[k]));
    for (int k = 0; k < runs; ++k) requests.push_back(frames[k].Request(slots[k], f > 0 ? s.hop_s : 0.0));
    std::vector<ParticleBank::StepResult> results(runs);
    ASSERT_TRUE(bank->Step(requests, results).ok());
    if (f < s.frames / 4) continue;
    for (const auto& r : results) {
      ASSERT_TRUE(r.status.ok());
      sum_sq += (r.state.mean.head<3>() - (s.p0 + s.v * t)).squaredNorm();
      ++scored;
    }
  }
  const double gpu = std::sqrt(sum_sq / scored);  // = the pooled per-run RMSE (equal frame counts)
  std::printf("pooled rmse over %d runs: cpu %.4f m, gpu %.4f m (ratio %.3f)\n", runs, cpu, gpu, gpu / cpu);
  EXPECT_LT(gpu, 1.10 * cpu);
  EXPECT_GT(gpu, 0.90 * cpu);
}

TEST(ParticleBank, MemoryLimitRejectsAnOpenAndLeavesTheOtherSlotsWorking) {
  LOCALIZER_SKIP_WITHOUT_GPU();
  const CvScenario s;
  const engine::ParticleFilterOptions o = CvOptions(4096, 42);
  const std::size_t slot_bytes = pf::SlotLayout::For(o.particles).bytes;
  auto bank = NewBank(3 * slot_bytes + slot_bytes / 2);
  EXPECT_EQ(bank->memory_limit_bytes(), 3 * slot_bytes + slot_bytes / 2);
  std::vector<int> slots;
  for (int k = 0; k < 3; ++k) slots.push_back(OpenInitialised(*bank, s, o));
  EXPECT_EQ(bank->bytes_in_use(), 3 * slot_bytes);
  const auto refused = bank->Open(s.array, o);
  ASSERT_EQ(refused.status().code(), StatusCode::kResourceExhausted);
  EXPECT_NE(refused.status().message().find(std::to_string(slot_bytes)), std::string::npos)
      << refused.status().message();
  EXPECT_NE(refused.status().message().find(std::to_string(slot_bytes / 2)), std::string::npos)
      << refused.status().message();
  EXPECT_EQ(bank->open_slots(), 3);
  EXPECT_EQ(bank->bytes_in_use(), 3 * slot_bytes);
  // The refused Open left the others intact: slot 1 steps as a session alone does.
  const auto reference = RunAlone(o, 5);
  std::mt19937_64 rng(5);
  for (int f = 0; f < 5; ++f) {
    const Frame frame = MakeFrame(s, f * s.hop_s, rng);
    const ParticleBank::StepRequest request = frame.Request(slots[1], f > 0 ? s.hop_s : 0.0);
    ParticleBank::StepResult result;
    ASSERT_TRUE(bank->Step({&request, 1}, {&result, 1}).ok());
    ExpectIdentical(result, reference[static_cast<size_t>(f)]);
  }
  // Closing one makes room again.
  bank->Close(slots[0]);
  EXPECT_EQ(bank->bytes_in_use(), 2 * slot_bytes);
  EXPECT_TRUE(bank->Open(s.array, o).ok());
}

TEST(ParticleBank, CloseFreesTheSlotsMemory) {
  LOCALIZER_SKIP_WITHOUT_GPU();
  const CvScenario s;
  auto bank = NewBank();
  EXPECT_EQ(bank->bytes_in_use(), 0u);
  const int a = *bank->Open(s.array, CvOptions(4096, 1));
  const int b = *bank->Open(s.array, CvOptions(100000, 2));
  EXPECT_EQ(bank->open_slots(), 2);
  EXPECT_EQ(bank->bytes_in_use(), pf::SlotLayout::For(4096).bytes + pf::SlotLayout::For(100000).bytes);
  bank->Close(b);
  EXPECT_EQ(bank->bytes_in_use(), pf::SlotLayout::For(4096).bytes);
  bank->Close(b);  // twice: no-op
  bank->Close(a);
  EXPECT_EQ(bank->bytes_in_use(), 0u);
  EXPECT_EQ(bank->open_slots(), 0);
  EXPECT_EQ(*bank->Open(s.array, CvOptions(16, 3)), 0);  // numbers are reused
}

TEST(ParticleBank, OpenRejectsMoreThanSixteenSensorsAndBadOptions) {
  LOCALIZER_SKIP_WITHOUT_GPU();
  auto bank = NewBank();
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> u(-2.0, 2.0);
  std::vector<engine::Vec3> positions;
  for (int k = 0; k < 17; ++k) positions.emplace_back(u(rng), u(rng), u(rng));
  EXPECT_EQ(bank->Open(*engine::ArrayGeometry::Create(positions, 343.0), CvOptions()).status().code(),
            StatusCode::kInvalidArgument);
  engine::ParticleFilterOptions bad = CvOptions();
  bad.particles = 3;
  EXPECT_EQ(bank->Open(Tetrahedron(2.0, engine::Vec3::Zero(), 343.0), bad).status().code(),
            StatusCode::kInvalidArgument);
  EXPECT_EQ(bank->bytes_in_use(), 0u);
}

TEST(ParticleBank, BadRequestsGetTheirOwnStatusAndTheOthersRun) {
  LOCALIZER_SKIP_WITHOUT_GPU();
  const CvScenario s;
  auto bank = NewBank();
  const int ready = OpenInitialised(*bank, s, CvOptions(4096, 1));
  const int fresh = *bank->Open(s.array, CvOptions(4096, 2));  // not initialised
  std::mt19937_64 rng(1);
  const Frame frame = MakeFrame(s, 0.0, rng);
  Frame short_frame = frame;
  short_frame.m.pairs.pop_back();
  const std::vector<ParticleBank::StepRequest> requests = {frame.Request(ready, 0.1), frame.Request(fresh, 0.1),
                                                           frame.Request(ready, 0.1), frame.Request(99, 0.1),
                                                           short_frame.Request(ready, 0.1)};
  std::vector<ParticleBank::StepResult> results(requests.size());
  ASSERT_TRUE(bank->Step(requests, results).ok());
  EXPECT_TRUE(results[0].status.ok()) << results[0].status.ToString();
  EXPECT_EQ(results[1].status.code(), StatusCode::kFailedPrecondition);
  EXPECT_EQ(results[2].status.code(), StatusCode::kInvalidArgument);  // ready named twice
  EXPECT_EQ(results[3].status.code(), StatusCode::kInvalidArgument);  // not open
  EXPECT_EQ(results[4].status.code(), StatusCode::kInvalidArgument);  // ready named twice
  std::vector<ParticleBank::StepResult> one(1);
  EXPECT_EQ(bank->Step(requests, one).code(), StatusCode::kInvalidArgument);
  const ParticleBank::StepRequest bad = short_frame.Request(ready, 0.1);
  ASSERT_TRUE(bank->Step({&bad, 1}, one).ok());
  EXPECT_EQ(one[0].status.code(), StatusCode::kInvalidArgument);  // pair count
  EXPECT_EQ(bank->Moments(fresh).status().code(), StatusCode::kFailedPrecondition);
}

TEST(ParticleBank, PredictOnlyMovesTheMeanAndKeepsTheEss) {
  LOCALIZER_SKIP_WITHOUT_GPU();
  const CvScenario s;
  auto bank = NewBank();
  engine::ParticleFilterOptions o = CvOptions(1 << 16, 3);
  o.accel_noise_mps2 = 0.0;  // deterministic motion: the mean moves by v dt exactly
  auto slot = bank->Open(s.array, o);
  ASSERT_TRUE(slot.ok());
  engine::TrackState belief;
  belief.mean << 3, -2, -9, 0.5, -0.25, 0.1;
  belief.covariance.diagonal() << 0.01, 0.01, 0.01, 0.0, 0.0, 0.0;
  ASSERT_TRUE(bank->InitialiseGaussian(*slot, belief.mean, CovarianceRoot(belief.covariance)).ok());
  const auto before = bank->Moments(*slot);
  ASSERT_TRUE(before.ok());
  const ParticleBank::StepRequest request{*slot, 2.0, nullptr, nullptr, nullptr};
  ParticleBank::StepResult result;
  ASSERT_TRUE(bank->Step({&request, 1}, {&result, 1}).ok());
  ASSERT_TRUE(result.status.ok());
  EXPECT_EQ(result.ess, o.particles);
  EXPECT_FALSE(result.resampled);
  for (int a = 0; a < 3; ++a) {
    EXPECT_NEAR(result.state.mean(a), before->mean(a) + 2.0 * before->mean(3 + a), 1e-4) << a;
  }
  for (const auto& in : result.innovations) {
    EXPECT_EQ(in.mean_s, 0.0);
    EXPECT_EQ(in.predicted_var_s2, 0.0);
  }
  // Moments recomputes from the same particles and weights with the same kernels.
  const auto after = bank->Moments(*slot);
  ASSERT_TRUE(after.ok());
  EXPECT_EQ(after->mean, result.state.mean);
  EXPECT_EQ(after->covariance, result.state.covariance);
}

TEST(ParticleBank, InitialisationMatchesTheRequestedBeliefAndRegion) {
  LOCALIZER_SKIP_WITHOUT_GPU();
  const engine::ArrayGeometry array = Tetrahedron(2.0, engine::Vec3(10, 20, -5), 343.0);
  auto bank = NewBank();
  engine::ParticleFilterOptions o = CvOptions(1 << 16, 5);
  const int slot = *bank->Open(array, o);
  engine::TrackState belief;
  belief.mean << 13, 18, -4, 0.5, 0, -0.5;
  belief.covariance.diagonal() << 0.25, 1.0, 4.0, 0.01, 0.04, 0.09;
  belief.covariance(0, 1) = belief.covariance(1, 0) = 0.3;
  ASSERT_TRUE(bank->InitialiseGaussian(slot, belief.mean, CovarianceRoot(belief.covariance)).ok());
  auto state = bank->Moments(slot);
  ASSERT_TRUE(state.ok());
  // 65536 draws: standard error of a mean ~ sigma / 256, of a variance ~ 0.6 %.
  for (int k = 0; k < 6; ++k) {
    EXPECT_NEAR(state->mean(k), belief.mean(k), 5.0 * std::sqrt(belief.covariance(k, k)) / 256.0) << k;
    EXPECT_NEAR(state->covariance(k, k), belief.covariance(k, k), 0.04 * belief.covariance(k, k)) << k;
  }
  EXPECT_NEAR(state->covariance(0, 1), 0.3, 0.02);
  const engine::Vec3 lo(8, 15, -9), hi(12, 25, -3);
  ASSERT_TRUE(bank->InitialiseRegion(slot, lo, hi, 0.5).ok());
  state = bank->Moments(slot);
  ASSERT_TRUE(state.ok());
  for (int a = 0; a < 3; ++a) {
    const double span = hi(a) - lo(a);
    EXPECT_NEAR(state->mean(a), 0.5 * (lo(a) + hi(a)), 5.0 * span / std::sqrt(12.0) / 256.0) << a;
    EXPECT_NEAR(state->covariance(a, a), span * span / 12.0, 0.04 * span * span / 12.0) << a;
    EXPECT_NEAR(state->mean(3 + a), 0.0, 5.0 * 0.5 / 256.0);
    EXPECT_NEAR(state->covariance(3 + a, 3 + a), 0.25, 0.01);
  }
  EXPECT_EQ(bank->InitialiseRegion(slot, hi, lo, 0.5).code(), StatusCode::kInvalidArgument);
}

// With every particle at one state the prior innovation of each pair is d - h(state): the
// NIS the CPU filter reports from its innovations is the bank's.
TEST(ParticleBank, InnovationsMatchTheCpuFilterOnAPointCloud) {
  LOCALIZER_SKIP_WITHOUT_GPU();
  const CvScenario s;
  const engine::ParticleFilterOptions o = CvOptions(256, 3);
  engine::TrackState point;
  point.mean << 5.0, -3.0, -8.5, -1.0, 0.8, 0.1;
  auto cpu = std::move(engine::ParticleFilter::Create(s.array, o)).value();
  ASSERT_TRUE(cpu->Initialise(point).ok());
  auto bank = NewBank();
  const int slot = *bank->Open(s.array, o);
  ASSERT_TRUE(bank->InitialiseGaussian(slot, point.mean, engine::Mat6::Zero()).ok());
  std::mt19937_64 rng(2);
  const Frame frame = MakeFrame(s, 1.0, rng);
  const auto report = cpu->Update(frame.m);
  ASSERT_TRUE(report.ok());
  const ParticleBank::StepRequest request = frame.Request(slot, 0.0);
  ParticleBank::StepResult result;
  ASSERT_TRUE(bank->Step({&request, 1}, {&result, 1}).ok());
  ASSERT_TRUE(result.status.ok());
  double nis = 0.0;
  for (const auto& in : result.innovations) nis += in.mean_s * in.mean_s / (8e-6 * 8e-6 + in.predicted_var_s2);
  EXPECT_GT(report->nis, 1.0);
  EXPECT_NEAR(nis, report->nis, 1e-4 * report->nis);
  EXPECT_NEAR(result.ess, 256.0, 1e-6);  // identical particles: identical weights
}

}  // namespace
}  // namespace localizer::gpu

#else  // !LOCALIZER_HAVE_CUDA

#include <gtest/gtest.h>

TEST(ParticleBank, NeedsTheCudaBuild) { GTEST_SKIP() << "built without CUDA: gpu/filters is not compiled"; }

#endif  // LOCALIZER_HAVE_CUDA
