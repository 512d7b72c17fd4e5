// The batched GPU GCC-PHAT stage (gpu/tdoa/gcc_batch.h) against the CPU estimator
// (engine::GccPhatEstimator) on the same simulated frames. Needs a device: every test skips
// with the reason where there is none.
//
// Sessions, frames, tolerances and comparisons: tests/gpu/gcc_test_sessions.h.
#include "gpu/tdoa/gcc_batch.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "engine/sim/simulator.h"
#include "engine/tdoa/gcc_phat.h"
#include "gpu/core/device_buffer.h"
#include "tests/gpu/gcc_test_sessions.h"
#include "tests/gpu/gpu_test_util.h"

namespace localizer::gpu {
namespace {

using engine::GccOptions;
using engine::Measurement;
using engine::PeakInterpolation;
using engine::Weighting;

using namespace gcc_testing;  // NOLINT: the shared fixtures of the GCC batch tests

TEST(GccBatch, SessionsWithDifferentArraysAndOptionsShareOneBatch) {
  LOCALIZER_SKIP_WITHOUT_GPU();
  // tetra-water (11025 Hz, 2 m) and tetra-air (48 kHz, 0.5 m): both N = 5120, 4 channels.
  std::vector<std::unique_ptr<Session>> sessions;
  sessions.push_back(MakeSession("tetra-water", Options(0, Weighting::kPhat, PeakInterpolation::kSinc, 300, 3000)));
  sessions.push_back(
      MakeSession("tetra-water", Options(0, Weighting::kScot, PeakInterpolation::kParabolic, 0, 0, false)));
  sessions.push_back(
      MakeSession("tetra-air", Options(0, Weighting::kPhatBeta, PeakInterpolation::kGaussian, 300, 8000)));
  sessions.push_back(MakeSession("tetra-air", Options(0, Weighting::kCc, PeakInterpolation::kSinc, 0, 0)));
  GccOptions wide_margin = Options(0, Weighting::kPhat, PeakInterpolation::kSinc, 300, 3000);
  wide_margin.lag_margin_samples = 40;
  sessions.push_back(MakeSession("tetra-water", wide_margin));
  for (const auto& s : sessions) ASSERT_EQ(s->plan.key(), sessions[0]->plan.key()) << s->plan.key().ToString();

  std::vector<Item> items;
  for (int round = 0; round < 3; ++round) {  // interleaved, as a dispatcher would collect them
    for (auto& s : sessions) items.push_back(MakeItem(*s, (round + 1) * s->last_start() / 4));
  }
  auto batch = MakeBatch(sessions[0]->plan, 16);
  ASSERT_NE(batch, nullptr);
  ExpectAllMatchCpu(RunOnGpu(*batch, items), items);
}

TEST(GccBatch, BatchesOfOneSevenAndSixtyFourMatchTheCpu) {
  LOCALIZER_SKIP_WITHOUT_GPU();
  auto session = MakeSession("tetra-water", Options(0, Weighting::kPhat, PeakInterpolation::kSinc, 300, 3000));
  auto batch = MakeBatch(session->plan, 64);
  ASSERT_NE(batch, nullptr);
  for (int count : {1, 7, 64}) {
    SCOPED_TRACE("batch of " + std::to_string(count));
    const std::vector<Item> items = SpreadItems(*session, count);
    ExpectAllMatchCpu(RunOnGpu(*batch, items), items);
  }
}

TEST(GccBatch, FullBatchOfACapacityThatIsNotAPowerOfTwo) {
  LOCALIZER_SKIP_WITHOUT_GPU();
  auto session = MakeSession("tetra-air", Options(0, Weighting::kPhat, PeakInterpolation::kSinc, 300, 8000));
  auto batch = MakeBatch(session->plan, 20);
  ASSERT_NE(batch, nullptr);
  EXPECT_EQ(batch->max_frames(), 20);
  for (int count : {20, 17, 9, 20}) {  // buckets 20, 20, 16, then 20 again from the cache
    SCOPED_TRACE("batch of " + std::to_string(count));
    const std::vector<Item> items = SpreadItems(*session, count);
    ExpectAllMatchCpu(RunOnGpu(*batch, items), items);
  }
}

TEST(GccBatch, EightChannelArray) {
  LOCALIZER_SKIP_WITHOUT_GPU();
  auto session = MakeSession("turn-multipath", Options(0, Weighting::kPhat, PeakInterpolation::kSinc, 300, 3000));
  EXPECT_EQ(session->plan.key().channels, 8);
  auto batch = MakeBatch(session->plan, 8);
  ASSERT_NE(batch, nullptr);
  const std::vector<Item> items = SpreadItems(*session, 5);
  ExpectAllMatchCpu(RunOnGpu(*batch, items), items);
}

// A session's estimator leaves the candidates to its own thread (GccJob::tails): what it
// picks with FinishCandidates is what the batch picks itself, on an 8-channel array with echoes
// (several candidates per pair) and on a frame without a kept window.
TEST(GccBatch, CandidatesFinishedByTheCallerAreTheBatchsOwn) {
  LOCALIZER_SKIP_WITHOUT_GPU();
  for (const bool keep_gcc : {true, false}) {
    SCOPED_TRACE(keep_gcc ? "window kept" : "no window");
    auto session =
        MakeSession("turn-multipath", Options(0, Weighting::kPhat, PeakInterpolation::kSinc, 300, 3000, keep_gcc));
    auto batch = MakeBatch(session->plan, 8);
    ASSERT_NE(batch, nullptr);
    const std::vector<Item> items = SpreadItems(*session, 5);
    const std::vector<Measurement> whole = RunOnGpu(*batch, items);
    std::vector<Measurement> out(items.size());
    std::vector<std::vector<GccPairTail>> tails(items.size());
    std::vector<GccJob> jobs;
    for (std::size_t i = 0; i < items.size(); ++i) {
      GccJob job{&session->plan, items[i].frame.data(), items[i].t_s, &out[i]};
      job.tails = &tails[i];
      jobs.push_back(job);
    }
    ASSERT_TRUE(batch->Run(jobs).ok());
    std::vector<engine::WindowExtremum> scratch;
    std::size_t most = 0;
    for (std::size_t i = 0; i < items.size(); ++i) {
      for (const auto& pair : out[i].pairs) EXPECT_LE(pair.candidates.size(), 1u);  // the main peak, until finished
      FinishCandidates(session->plan, tails[i], &out[i], &scratch);
      ExpectIdentical(out[i], whole[i]);
      for (const auto& pair : out[i].pairs) most = std::max(most, pair.candidates.size());
    }
    EXPECT_EQ(most, keep_gcc ? 4u : 1u);
  }
}

TEST(GccBatch, SilentFrameGivesZeroesLikeTheCpu) {
  LOCALIZER_SKIP_WITHOUT_GPU();
  auto session = MakeSession("tetra-water", Options(0, Weighting::kPhat, PeakInterpolation::kSinc, 300, 3000));
  std::vector<Item> items = SpreadItems(*session, 3);
  items[1].frame.assign(items[1].frame.size(), 0.0f);
  ASSERT_TRUE(session->cpu->Estimate(items[1].frame.data(), kFrameSamples, items[1].t_s, &items[1].cpu).ok());
  auto batch = MakeBatch(session->plan, 4);
  ASSERT_NE(batch, nullptr);
  const std::vector<Measurement> gpu = RunOnGpu(*batch, items);
  ExpectAllMatchCpu(gpu, items);
  for (const engine::PairMeasurement& pair : gpu[1].pairs) {
    EXPECT_EQ(pair.delay_s, 0.0);
    EXPECT_EQ(pair.quality, 0.0);
    EXPECT_EQ(pair.peak_value, 0.0);
    EXPECT_EQ(pair.peak_snr, 0.0);
    EXPECT_TRUE(std::all_of(pair.gcc.begin(), pair.gcc.end(), [](float v) { return v == 0.0f; }));
  }
}

TEST(GccBatch, SameInputGivesBitIdenticalOutput) {
  LOCALIZER_SKIP_WITHOUT_GPU();
  auto session = MakeSession("tetra-water", Options(0, Weighting::kPhatBeta, PeakInterpolation::kSinc, 300, 3000));
  auto batch = MakeBatch(session->plan, 16);
  ASSERT_NE(batch, nullptr);
  std::vector<Item> items = SpreadItems(*session, 6);
  items.push_back(items[0]);  // the same frame again in another slot of the same batch
  const std::vector<Measurement> first = RunOnGpu(*batch, items);
  const std::vector<Measurement> second = RunOnGpu(*batch, items);
  for (std::size_t i = 0; i < items.size(); ++i) ExpectIdentical(first[i], second[i]);
  ExpectIdentical(first[0], first.back());
}

TEST(GccBatch, ResultsDoNotDependOnTheBatchBucket) {
  LOCALIZER_SKIP_WITHOUT_GPU();
  // gpu_backend.h promises that a frame's result does not depend on which other frames share
  // its batch. Within one cuFFT plan rows are independent; across buckets (other plans of the
  // same N, other batch counts) this checks that cuFFT computes each row the same way.
  auto session = MakeSession("tetra-water", Options(0, Weighting::kPhat, PeakInterpolation::kSinc, 300, 3000));
  auto batch = MakeBatch(session->plan, 64);
  ASSERT_NE(batch, nullptr);
  const std::vector<Item> items = SpreadItems(*session, 40);
  const std::vector<Measurement> together = RunOnGpu(*batch, items);  // bucket 64
  for (int count : {1, 2, 5, 16}) {                                   // buckets 1, 2, 8, 16
    SCOPED_TRACE("batch of " + std::to_string(count));
    const std::vector<Item> few(items.begin(), items.begin() + count);
    const std::vector<Measurement> apart = RunOnGpu(*batch, few);
    for (int i = 0; i < count; ++i) ExpectIdentical(together[i], apart[i]);
  }
}

TEST(GccBatch, PinnedFramesAreReadInPlaceWithTheSameResults) {
  LOCALIZER_SKIP_WITHOUT_GPU();
  // A session that stages its frame in its own pinned buffer (GpuTdoaEstimator does) gets
  // exactly what a pageable frame copied by the batch gets, mixed in one batch.
  auto session = MakeSession("tetra-water", Options(0, Weighting::kPhat, PeakInterpolation::kSinc, 300, 3000));
  auto batch = MakeBatch(session->plan, 8);
  ASSERT_NE(batch, nullptr);
  const std::vector<Item> items = SpreadItems(*session, 6);
  const std::vector<Measurement> pageable = RunOnGpu(*batch, items);
  const std::size_t frame_floats = items[0].frame.size();
  auto pinned = PinnedBuffer<float>::Allocate(frame_floats * items.size());
  ASSERT_TRUE(pinned.ok()) << pinned.status().ToString();
  std::vector<Measurement> out(items.size());
  std::vector<GccJob> jobs;
  for (std::size_t i = 0; i < items.size(); ++i) {
    float* frame = pinned->data() + i * frame_floats;
    std::copy(items[i].frame.begin(), items[i].frame.end(), frame);
    GccJob job{&session->plan, frame, items[i].t_s, &out[i]};
    job.frame_pinned = i % 2 == 0;  // every other one: both paths in one batch
    if (!job.frame_pinned) job.frame = items[i].frame.data();
    jobs.push_back(job);
  }
  ASSERT_TRUE(batch->Run(jobs).ok());
  for (std::size_t i = 0; i < items.size(); ++i) {
    SCOPED_TRACE("job " + std::to_string(i));
    ExpectIdentical(out[i], pageable[i]);
    ExpectMatchesCpu(out[i], items[i].cpu);
  }
}

TEST(GccBatch, NonFiniteSampleFailsOnlyItsJob) {
  LOCALIZER_SKIP_WITHOUT_GPU();
  auto session = MakeSession("tetra-water", Options(0, Weighting::kPhat, PeakInterpolation::kSinc, 300, 3000));
  std::vector<Item> items = SpreadItems(*session, 3);
  items[1].frame[2 * kFrameSamples + 100] = std::numeric_limits<float>::quiet_NaN();  // channel 2
  auto batch = MakeBatch(session->plan, 4);
  ASSERT_NE(batch, nullptr);

  std::vector<Measurement> out(3);
  out[1].t_s = -7.0;  // must stay untouched
  std::vector<Status> statuses(3);
  std::vector<GccJob> jobs;
  for (int i = 0; i < 3; ++i)
    jobs.push_back({&session->plan, items[i].frame.data(), items[i].t_s, &out[i], &statuses[i]});
  ASSERT_TRUE(batch->Run(jobs).ok());
  EXPECT_TRUE(statuses[0].ok());
  EXPECT_TRUE(statuses[2].ok());
  EXPECT_EQ(statuses[1].code(), StatusCode::kInvalidArgument);
  EXPECT_NE(statuses[1].message().find("channel 2"), std::string::npos) << statuses[1].message();
  EXPECT_EQ(out[1].t_s, -7.0);
  EXPECT_TRUE(out[1].pairs.empty());
  ExpectMatchesCpu(out[0], items[0].cpu);
  ExpectMatchesCpu(out[2], items[2].cpu);

  // Without status pointers the batch reports the job and still fills the others.
  for (GccJob& job : jobs) job.status = nullptr;
  out.assign(3, Measurement{});
  const Status status = batch->Run(jobs);
  EXPECT_EQ(status.code(), StatusCode::kInvalidArgument);
  EXPECT_NE(status.message().find("job 1: channel 2"), std::string::npos) << status.message();
  ExpectMatchesCpu(out[2], items[2].cpu);
}

TEST(GccBatch, MalformedJobListsAreRejectedBeforeAnyWork) {
  LOCALIZER_SKIP_WITHOUT_GPU();
  auto water = MakeSession("tetra-water", Options(0, Weighting::kPhat, PeakInterpolation::kSinc, 300, 3000));
  GccOptions short_frames = Options(0, Weighting::kPhat, PeakInterpolation::kSinc, 300, 3000);
  short_frames.frame_samples = 1024;
  auto other_key = MakeSession("tetra-water", short_frames);
  auto batch = MakeBatch(water->plan, 2);
  ASSERT_NE(batch, nullptr);
  const std::vector<float> frame = water->Frame(0);
  Measurement m;
  EXPECT_EQ(batch->Run({}).code(), StatusCode::kInvalidArgument);
  const GccJob good{&water->plan, frame.data(), 0.0, &m};
  const std::vector<GccJob> too_many(3, good);
  EXPECT_EQ(batch->Run(too_many).code(), StatusCode::kInvalidArgument);
  const GccJob null_out{&water->plan, frame.data(), 0.0, nullptr};
  EXPECT_EQ(batch->Run({&null_out, 1}).code(), StatusCode::kInvalidArgument);
  const GccJob wrong_key{&other_key->plan, frame.data(), 0.0, &m};
  const Status status = batch->Run({&wrong_key, 1});
  EXPECT_EQ(status.code(), StatusCode::kInvalidArgument);
  EXPECT_NE(status.message().find("frame_samples=1024"), std::string::npos) << status.message();
  EXPECT_TRUE(m.pairs.empty());
}

TEST(GccBatch, TimingIsRecordedWhenAskedFor) {
  LOCALIZER_SKIP_WITHOUT_GPU();
  auto session = MakeSession("tetra-water", Options(0, Weighting::kPhat, PeakInterpolation::kSinc, 300, 3000));
  auto batch = MakeBatch(session->plan, 8, /*timing=*/true);
  ASSERT_NE(batch, nullptr);
  const std::vector<Item> items = SpreadItems(*session, 8);
  RunOnGpu(*batch, items);
  const GccBatch::Timing t = batch->last_timing();
  EXPECT_GT(t.fft_ms, 0.0f);
  EXPECT_GE(t.device_ms, t.fft_ms);
  EXPECT_GE(t.total_ms, t.device_ms);
}

}  // namespace
}  // namespace localizer::gpu
