// The device sample rings of the GCC batch (GccJob::ring, gpu/tdoa/sample_ring.h) and of
// GpuTdoaEstimator: a frame read back from a session's ring gives exactly (bit for bit) what
// the same frame sent whole gives, so everything gcc_batch_test.cc holds against the CPU
// still holds; only the new samples cross the bus. Needs a device: every test skips with the
// reason where there is none. The ring's index maths are tested on the host in
// sample_ring_test.cc.
//
// gpu/tdoa is compiled only in CUDA builds (gpu/CMakeLists.txt); elsewhere this test
// reports itself skipped.
#if defined(LOCALIZER_HAVE_CUDA)

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "gpu/backend/gpu_runtime.h"
#include "gpu/backend/gpu_tdoa_estimator.h"
#include "gpu/core/device_buffer.h"
#include "gpu/tdoa/gcc_batch.h"
#include "gpu/tdoa/sample_ring.h"
#include "tests/gpu/gcc_test_sessions.h"
#include "tests/gpu/gpu_test_util.h"

namespace localizer::gpu {
namespace {

using engine::Measurement;
using engine::PeakInterpolation;
using engine::Weighting;
using gcc_testing::ExpectIdentical;
using gcc_testing::ExpectMatchesCpu;
using gcc_testing::Item;
using gcc_testing::kFrameSamples;
using gcc_testing::MakeBatch;
using gcc_testing::MakeItem;
using gcc_testing::MakeSession;
using gcc_testing::Options;
using gcc_testing::RunOnGpu;
using gcc_testing::Session;

SampleRing MakeRing(int channels, int capacity) {
  auto ring = SampleRing::Create(channels, capacity);
  EXPECT_TRUE(ring.ok()) << ring.status().ToString();
  return ring.ok() ? std::move(ring).value() : SampleRing();
}

// A session streaming through its ring: frames every `hop` samples, each job bringing only
// the samples the ring lacks.
struct RingStream {
  Session* session;
  SampleRing ring;
  int hop;
  int64_t next_start = 0;
};

// One round: every stream's next frame as a ring job, in one Run; the same frames as whole
// frames in another Run; the two must be identical and match the CPU.
void RunRound(GccBatch& batch, std::vector<RingStream>& streams) {
  std::vector<Item> items;
  std::vector<int> fresh;
  for (RingStream& s : streams) {
    items.push_back(MakeItem(*s.session, s.next_start));
    fresh.push_back(s.ring.valid() ? std::min(s.hop, kFrameSamples) : kFrameSamples);
    s.next_start += s.hop;
  }
  std::vector<Measurement> out(items.size());
  std::vector<GccJob> jobs;
  std::size_t bytes = 0;
  for (std::size_t i = 0; i < items.size(); ++i) {
    GccJob job{&items[i].session->plan, items[i].frame.data(), items[i].t_s, &out[i]};
    job.ring = &streams[i].ring;
    job.ring_new_samples = fresh[i];
    bytes += sizeof(float) * items[i].session->plan.channels() * fresh[i];
    jobs.push_back(job);
  }
  ASSERT_TRUE(batch.Run(jobs).ok());
  EXPECT_EQ(batch.last_frame_bytes_over_bus(), bytes);
  const std::vector<Measurement> whole = RunOnGpu(batch, items);
  for (std::size_t i = 0; i < items.size(); ++i) {
    SCOPED_TRACE("stream " + std::to_string(i));
    ExpectIdentical(out[i], whole[i]);
    ExpectMatchesCpu(out[i], items[i].cpu);
  }
}

TEST(GccRing, AFiftyPercentHopSendsHalfTheBytesAndGivesTheSameResults) {
  LOCALIZER_SKIP_WITHOUT_GPU();
  // 7 frames at a 2048-sample hop reach sample 16 384: 1.5 s at tetra-water's 11 025 Hz.
  auto session = MakeSession("tetra-water", Options(0, Weighting::kPhat, PeakInterpolation::kSinc, 300, 3000), 2.0);
  auto batch = MakeBatch(session->plan, 4);
  ASSERT_NE(batch, nullptr);
  std::vector<RingStream> streams;
  streams.push_back({session.get(), MakeRing(session->plan.channels(), kFrameSamples), kFrameSamples / 2});
  RunRound(*batch, streams);  // the first frame goes whole
  EXPECT_EQ(batch->last_frame_bytes_over_bus() / 2, sizeof(float) * 4 * kFrameSamples / 2);
  for (int round = 0; round < 6; ++round) {
    RunRound(*batch, streams);
    EXPECT_EQ(streams[0].ring.total(), kFrameSamples + (round + 1) * kFrameSamples / 2);
  }
}

// Rings of other capacities and hops that do not divide them, so frames start anywhere and
// wrap; many sessions in one batch, over enough rounds to wrap each ring several times.
TEST(GccRing, ManySessionsRingsWrapAndStayBitIdenticalToWholeFrames) {
  LOCALIZER_SKIP_WITHOUT_GPU();
  auto water = MakeSession("tetra-water", Options(0, Weighting::kPhat, PeakInterpolation::kSinc, 300, 3000), 3.0);
  auto beta = MakeSession("tetra-water", Options(0, Weighting::kPhatBeta, PeakInterpolation::kParabolic, 0, 0), 3.0);
  auto batch = MakeBatch(water->plan, 16);
  ASSERT_NE(batch, nullptr);
  std::vector<RingStream> streams;
  const int hops[] = {2048, 1000, 4096, 1, 3333, 2048, 777, 4095};
  const int capacities[] = {4096, 4096, 4096, 5000, 4096, 8191, 4100, 4096};
  for (int i = 0; i < 8; ++i) {
    Session* s = i % 2 == 0 ? water.get() : beta.get();
    streams.push_back({s, MakeRing(s->plan.channels(), capacities[i]), hops[i]});
  }
  for (int round = 0; round < 6; ++round) {
    SCOPED_TRACE("round " + std::to_string(round));
    RunRound(*batch, streams);
  }
}

TEST(GccRing, MisusedRingsAreRejectedBeforeAnyWorkAndKeepTheirState) {
  LOCALIZER_SKIP_WITHOUT_GPU();
  auto session = MakeSession("tetra-water", Options(0, Weighting::kPhat, PeakInterpolation::kSinc, 300, 3000));
  auto batch = MakeBatch(session->plan, 4);
  ASSERT_NE(batch, nullptr);
  const Item item = MakeItem(*session, 0);
  Measurement out;
  SampleRing ring = MakeRing(4, kFrameSamples);
  const auto run = [&](SampleRing* r, int fresh) {
    GccJob job{&session->plan, item.frame.data(), item.t_s, &out};
    job.ring = r;
    job.ring_new_samples = fresh;
    return batch->Run({&job, 1});
  };
  EXPECT_EQ(run(&ring, kFrameSamples / 2).code(), StatusCode::kInvalidArgument);  // an invalid ring needs a frame
  EXPECT_EQ(run(&ring, 0).code(), StatusCode::kInvalidArgument);
  EXPECT_EQ(run(&ring, kFrameSamples + 1).code(), StatusCode::kInvalidArgument);
  SampleRing three = MakeRing(3, kFrameSamples), short_ring = MakeRing(4, kFrameSamples - 1);
  EXPECT_EQ(run(&three, kFrameSamples).code(), StatusCode::kInvalidArgument);
  EXPECT_EQ(run(&short_ring, kFrameSamples).code(), StatusCode::kInvalidArgument);
  EXPECT_FALSE(ring.valid());
  ASSERT_TRUE(run(&ring, kFrameSamples).ok());
  EXPECT_EQ(ring.total(), kFrameSamples);
  Measurement second;
  GccJob a{&session->plan, item.frame.data(), item.t_s, &out}, b{&session->plan, item.frame.data(), item.t_s, &second};
  a.ring = b.ring = &ring;
  a.ring_new_samples = b.ring_new_samples = 1;
  const GccJob both[] = {a, b};
  const Status twice = batch->Run(both);
  EXPECT_EQ(twice.code(), StatusCode::kInvalidArgument);
  EXPECT_NE(twice.message().find("already used"), std::string::npos) << twice.message();
  EXPECT_EQ(ring.total(), kFrameSamples);
}

TEST(GccRing, ANonFiniteFrameIsAppendedAndTheNextFrameStillReadsBack) {
  LOCALIZER_SKIP_WITHOUT_GPU();
  auto session = MakeSession("tetra-water", Options(0, Weighting::kPhat, PeakInterpolation::kSinc, 300, 3000));
  auto batch = MakeBatch(session->plan, 2);
  ASSERT_NE(batch, nullptr);
  SampleRing ring = MakeRing(4, kFrameSamples);
  constexpr int kHop = kFrameSamples / 2;
  Item first = MakeItem(*session, 0), second = MakeItem(*session, kHop);
  first.frame[kFrameSamples - 10] = std::numeric_limits<float>::quiet_NaN();  // channel 0, in the overlap
  second.frame[kHop - 10] = first.frame[kFrameSamples - 10];
  Measurement out;
  Status job_status;
  GccJob job{&session->plan, first.frame.data(), first.t_s, &out, &job_status};
  job.ring = &ring;
  job.ring_new_samples = kFrameSamples;
  ASSERT_TRUE(batch->Run({&job, 1}).ok());
  EXPECT_EQ(job_status.code(), StatusCode::kInvalidArgument);
  EXPECT_EQ(ring.total(), kFrameSamples);
  job = GccJob{&session->plan, second.frame.data(), second.t_s, &out, &job_status};
  job.ring = &ring;
  job.ring_new_samples = kHop;
  ASSERT_TRUE(batch->Run({&job, 1}).ok());
  EXPECT_EQ(job_status.code(), StatusCode::kInvalidArgument);  // the NaN came back from the ring
  EXPECT_NE(job_status.message().find("channel 0"), std::string::npos) << job_status.message();
}

// GpuTdoaEstimator finds the overlap itself: a framer's stream with a 50 % hop, then a gap,
// then a frame whose overlap was altered (as despiking does), each equal to the frame sent
// whole through a batch of its own.
TEST(GccRing, TheEstimatorGivesWhatWholeFramesGive) {
  LOCALIZER_SKIP_WITHOUT_GPU();
  auto session = MakeSession("tetra-water", Options(0, Weighting::kPhat, PeakInterpolation::kSinc, 300, 3000), 3.0);
  auto runtime = GpuRuntime::Create(GpuBackendOptions{});
  ASSERT_TRUE(runtime.ok()) << runtime.status().ToString();
  auto estimator = GpuTdoaEstimator::Create(*runtime, session->array, session->options);
  ASSERT_TRUE(estimator.ok()) << estimator.status().ToString();
  auto batch = MakeBatch(session->plan, 1);
  ASSERT_NE(batch, nullptr);
  std::vector<int64_t> starts;
  for (int f = 0; f < 5; ++f) starts.push_back(int64_t{f} * kFrameSamples / 2);
  starts.push_back(starts.back() + 3 * kFrameSamples);  // a gap
  starts.push_back(starts.back() + 1000);
  starts.push_back(starts.back() + 1000);  // altered below
  starts.push_back(starts.back() + 1000);
  for (std::size_t f = 0; f < starts.size(); ++f) {
    SCOPED_TRACE("frame " + std::to_string(f));
    Item item = MakeItem(*session, starts[f]);
    if (f == 7) {
      item.frame[3 * kFrameSamples + 5] *= 0.5f;  // channel 3, in the overlap
      ASSERT_TRUE(session->cpu->Estimate(item.frame.data(), kFrameSamples, item.t_s, &item.cpu).ok());
    }
    Measurement ring_out;
    ASSERT_TRUE((*estimator)->Estimate(item.frame.data(), kFrameSamples, item.t_s, &ring_out).ok());
    const std::vector<Measurement> whole = RunOnGpu(*batch, {item});
    ExpectIdentical(ring_out, whole[0]);
    ExpectMatchesCpu(ring_out, item.cpu);
  }
}

}  // namespace
}  // namespace localizer::gpu

#else

#include <gtest/gtest.h>

TEST(GccRing, NeedsTheCudaBuild) { GTEST_SKIP() << "built without CUDA: gpu/tdoa is not compiled"; }

#endif
