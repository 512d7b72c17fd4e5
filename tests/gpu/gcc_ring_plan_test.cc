// A GCC batch's ring jobs on the host: the descriptors gcc_batch.cc builds for each job
// (gpu/tdoa/frame_sources.cuh) applied exactly as the append and pack kernels index them,
// with host vectors standing in for the device rings. Over rounds of batches mixing ring jobs
// (random hops, some re-sent whole, rings of several capacities) and whole-frame jobs, every
// frame the pack would read equals the job's frame bit for bit, and the appends read nothing
// but the samples the batch staged. The device test of the same (gcc_ring_test.cc) skips
// without a GPU; this one runs wherever CUDA compiles.
//
// gpu/tdoa is compiled only in CUDA builds (gpu/CMakeLists.txt); elsewhere this test
// reports itself skipped.
#if defined(LOCALIZER_HAVE_CUDA)

#include <gtest/gtest.h>

#include <cstring>
#include <limits>
#include <random>
#include <vector>

#include "gpu/tdoa/frame_overlap.h"
#include "gpu/tdoa/frame_sources.cuh"

namespace localizer::gpu {
namespace {

constexpr int kChannels = 4;

// A session: its stream (per channel), its framer's hop, its "device" ring.
struct Stream {
  int hop = 1;
  int capacity = 0;  // 0: no ring (whole-frame jobs)
  std::vector<std::vector<float>> samples = std::vector<std::vector<float>>(kChannels);
  std::vector<float> ring;
  int64_t total = 0;
  bool valid = false;
  std::vector<float> previous;  // the last frame (what the estimator compares with)
  int64_t next_start = 0;
};

TEST(GccRingPlan, EmulatedBatchesReadEveryFrameBackBitForBit) {
  std::mt19937 rng(2026);
  std::uniform_real_distribution<float> value(-1.0f, 1.0f);
  std::uniform_int_distribution<int> coin(0, 7);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  for (int frame_samples : {8, 37, 64}) {
    SCOPED_TRACE("F " + std::to_string(frame_samples));
    std::vector<Stream> streams(9);
    for (std::size_t k = 0; k < streams.size(); ++k) {
      Stream& s = streams[k];
      s.hop = 1 + static_cast<int>(rng() % (frame_samples + 4));  // some hops leave gaps
      s.capacity = k == 0 ? 0 : frame_samples + static_cast<int>(rng() % 3) * static_cast<int>(k);
      s.ring.assign(static_cast<std::size_t>(kChannels) * s.capacity, nan);
    }
    int reused = 0;
    for (int round = 0; round < 25; ++round) {
      // The batch: each stream's next frame, the samples the ring lacks, the staging.
      const std::size_t frame_floats = static_cast<std::size_t>(kChannels) * frame_samples;
      std::vector<std::vector<float>> frames, staged;
      std::vector<GccFrameSource> sources;
      std::vector<GccRingAppend> appends;
      std::vector<int> fresh;
      for (Stream& s : streams) {
        const std::size_t end = static_cast<std::size_t>(s.next_start) + frame_samples;
        for (auto& row : s.samples) {
          while (row.size() < end) row.push_back(value(rng));
        }
        std::vector<float> frame;
        for (const auto& row : s.samples) frame.insert(frame.end(), row.end() - frame_samples, row.end());
        int n = frame_samples;
        if (s.capacity > 0 && s.valid && coin(rng) != 0) {
          n = NewSampleCount(s.previous.data(), frame.data(), kChannels, frame_samples, s.hop);
        }
        reused += n < frame_samples;
        // Pageable frames: the batch stages only what the device reads; the rest stays NaN,
        // so a read outside it would show.
        std::vector<float> stage(frame_floats, nan);
        StageNewSamples(frame.data(), stage.data(), kChannels, frame_samples, n);
        frames.push_back(frame);
        staged.push_back(std::move(stage));
        fresh.push_back(n);
      }
      for (std::size_t k = 0; k < streams.size(); ++k) {
        Stream& s = streams[k];
        if (s.capacity == 0) {
          sources.push_back(WholeFrameSource(staged[k].data(), frame_samples));
          continue;
        }
        const RingJobDescriptors d = DescribeRingJob(staged[k].data(), s.ring.data(), s.capacity, s.valid ? s.total : 0,
                                                     frame_samples, fresh[k]);
        appends.push_back(d.append);
        sources.push_back(d.source);
      }
      // The append kernel over every (append, channel), then the pack kernel's reads.
      for (const GccRingAppend& a : appends) {
        for (int c = 0; c < kChannels; ++c) {
          for (int i = 0; i < a.count; ++i) *AppendTo(a, c, i) = *AppendFrom(a, c, i);
        }
      }
      for (std::size_t k = 0; k < streams.size(); ++k) {
        std::vector<float> read;
        for (int c = 0; c < kChannels; ++c) {
          for (int i = 0; i < frame_samples; ++i) read.push_back(*FrameSample(sources[k], c, i));
        }
        ASSERT_EQ(0, std::memcmp(read.data(), frames[k].data(), sizeof(float) * frame_floats))
            << "round " << round << " stream " << k << " new " << fresh[k] << " capacity " << streams[k].capacity;
      }
      // What GccBatch::Run does to the rings after the launch completed.
      for (std::size_t k = 0; k < streams.size(); ++k) {
        Stream& s = streams[k];
        s.total = (s.valid ? s.total : 0) + fresh[k];
        s.valid = s.capacity > 0;
        s.previous = frames[k];
        s.next_start += s.hop;
      }
    }
    EXPECT_GT(reused, 25);  // overlaps were found and used, not just whole frames re-sent
  }
}

TEST(GccRingPlan, AWholeFrameSourceIsTheFrameInPlace) {
  std::vector<float> frame(3 * 10);
  for (std::size_t i = 0; i < frame.size(); ++i) frame[i] = static_cast<float>(i);
  const GccFrameSource s = WholeFrameSource(frame.data(), 10);
  for (int c = 0; c < 3; ++c) {
    for (int i = 0; i < 10; ++i) EXPECT_EQ(FrameSample(s, c, i), frame.data() + c * 10 + i);
  }
}

}  // namespace
}  // namespace localizer::gpu

#else

#include <gtest/gtest.h>

TEST(GccRingPlan, NeedsTheCudaBuild) { GTEST_SKIP() << "built without CUDA: gpu/tdoa is not compiled"; }

#endif
