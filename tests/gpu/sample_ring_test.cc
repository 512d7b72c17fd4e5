// The device sample ring's index maths (gpu/tdoa/sample_ring.cuh) and the overlap finder
// (gpu/tdoa/frame_overlap.h) on the host, exhaustively for small sizes, against a plain model:
// the session's stream as one std::vector per channel. An emulated ring applies the plans
// exactly as the append and pack kernels do (gcc_kernels.cu); every frame read out of it
// must equal the stream's slice, bit for bit. Plain C++: runs in every build.
#include "gpu/tdoa/sample_ring.cuh"

#include <gtest/gtest.h>

#include <cstdint>
#include <cstring>
#include <limits>
#include <numeric>
#include <random>
#include <vector>

#include "gpu/tdoa/frame_overlap.h"

namespace localizer::gpu {
namespace {

// The stream so far, per channel, and a ring fed by the same blocks.
class Model {
 public:
  Model(int channels, int32_t capacity)
      : channels_(channels),
        capacity_(capacity),
        stream_(channels),
        ring_(static_cast<std::size_t>(channels) * capacity) {}

  // Appends block (channel-major, `n` samples per channel) to both, the ring as the append
  // kernel does: block sample source_first + i to row index Wrap(write_first, i, capacity).
  void Append(const std::vector<float>& block, int32_t n) {
    const ring::AppendPlan p = ring::PlanAppend(total_, n, capacity_);
    ASSERT_LE(p.count, capacity_);
    ASSERT_EQ(p.source_first + p.count, n);
    ASSERT_EQ(p.first_run, std::min(p.count, capacity_ - p.write_first));
    for (int c = 0; c < channels_; ++c) {
      for (int32_t i = 0; i < p.count; ++i) {
        Row(c)[ring::Wrap(p.write_first, i, capacity_)] = block[static_cast<std::size_t>(c) * n + p.source_first + i];
      }
      stream_[c].insert(stream_[c].end(), block.begin() + static_cast<std::ptrdiff_t>(c) * n,
                        block.begin() + static_cast<std::ptrdiff_t>(c + 1) * n);
    }
    total_ += n;
  }

  // The frame of F samples from row index `first`, as the pack kernel reads it.
  std::vector<float> ReadRing(int32_t first, int32_t frame_samples) const {
    std::vector<float> frame;
    for (int c = 0; c < channels_; ++c) {
      for (int32_t i = 0; i < frame_samples; ++i) frame.push_back(Row(c)[ring::Wrap(first, i, capacity_)]);
    }
    return frame;
  }

  std::vector<float> ReadStream(int64_t start, int32_t frame_samples) const {
    std::vector<float> frame;
    for (int c = 0; c < channels_; ++c) {
      frame.insert(frame.end(), stream_[c].begin() + start, stream_[c].begin() + start + frame_samples);
    }
    return frame;
  }

  int64_t total() const { return total_; }
  float* Row(int c) { return ring_.data() + static_cast<std::size_t>(c) * capacity_; }
  const float* Row(int c) const { return ring_.data() + static_cast<std::size_t>(c) * capacity_; }

 private:
  int channels_;
  int32_t capacity_;
  int64_t total_ = 0;
  std::vector<std::vector<float>> stream_;
  std::vector<float> ring_;
};

std::vector<float> RandomBlock(int channels, int32_t n, std::mt19937& rng) {
  std::uniform_real_distribution<float> value(-1.0f, 1.0f);
  std::vector<float> block(static_cast<std::size_t>(channels) * n);
  for (float& v : block) v = value(rng);
  return block;
}

// The frames of a framer (F, hop H, grid from stream sample 0) that a block ending at `total`
// after `n` new samples completed: f H + F in (total - n, total].
std::vector<int64_t> FramesCompleted(int64_t total, int32_t n, int32_t frame_samples, int32_t hop) {
  std::vector<int64_t> frames;
  for (int64_t f = 0; f * hop + frame_samples <= total; ++f) {
    if (f * hop + frame_samples > total - n) frames.push_back(f);
  }
  return frames;
}

TEST(SampleRing, WrapIsTheRemainderForEveryIndexOfSmallRings) {
  for (int32_t capacity = 1; capacity <= 16; ++capacity) {
    for (int32_t first = 0; first < capacity; ++first) {
      for (int32_t i = 0; i < capacity; ++i) ASSERT_EQ(ring::Wrap(first, i, capacity), (first + i) % capacity);
    }
  }
}

TEST(SampleRing, RowIndicesOfSixtyFourBitStreamPositions) {
  const int64_t t = (int64_t{1} << 40) + 12345;  // ~0.7 years at 48 kHz
  EXPECT_EQ(ring::RowIndexOf(t, 4096), static_cast<int32_t>(t % 4096));
  EXPECT_EQ(ring::RowIndexOf(t, 6000), static_cast<int32_t>(t % 6000));
  EXPECT_EQ(ring::FrameFirst(t / 2048, 2048, 4096), static_cast<int32_t>((t / 2048 * 2048) % 4096));
  const ring::RingJobPlan p = ring::PlanRingJob(t, 4096, 4096, 2048);
  EXPECT_EQ(p.append.write_first, static_cast<int32_t>(t % 4096));
  EXPECT_EQ(p.frame_first, static_cast<int32_t>((t + 2048 - 4096) % 4096));
}

// Blocks of random sizes (seeded), every frame/hop/block-size combination up to small
// bounds: after each append, every frame the block completed reads back from a ring of
// CapacityForAnyBlocks equal to the stream's slice.
TEST(SampleRing, FramesReadFromTheRingEqualTheStreamForRandomBlocks) {
  constexpr int kChannels = 2;
  std::mt19937 rng(20261203);
  int frames_checked = 0;
  for (int32_t frame_samples = 1; frame_samples <= 8; ++frame_samples) {
    for (int32_t hop = 1; hop <= 10; ++hop) {
      for (int32_t max_block = 1; max_block <= 11; ++max_block) {
        const auto capacity = static_cast<int32_t>(ring::CapacityForAnyBlocks(frame_samples, max_block));
        Model model(kChannels, capacity);
        std::uniform_int_distribution<int32_t> size(1, max_block);
        for (int b = 0; b < 40; ++b) {
          const int32_t n = size(rng);
          model.Append(RandomBlock(kChannels, n, rng), n);
          for (int64_t f : FramesCompleted(model.total(), n, frame_samples, hop)) {
            ASSERT_TRUE(ring::FrameReadable(f * hop, frame_samples, model.total(), capacity));
            ASSERT_EQ(model.ReadRing(ring::FrameFirst(f, hop, capacity), frame_samples),
                      model.ReadStream(f * hop, frame_samples))
                << "F " << frame_samples << " H " << hop << " max block " << max_block << " frame " << f;
            ++frames_checked;
          }
        }
      }
    }
  }
  EXPECT_GT(frames_checked, 10000);
}

// The worst alignment of the frame grid against a block of max_block samples: single samples
// until a frame starts n + F - 1 before the block's end. One sample less of ring loses it.
TEST(SampleRing, CapacityForAnyBlocksIsTight) {
  for (int32_t frame_samples = 1; frame_samples <= 8; ++frame_samples) {
    for (int32_t hop = 1; hop <= 10; ++hop) {
      for (int32_t n = 1; n <= 11; ++n) {
        const int64_t capacity = ring::CapacityForAnyBlocks(frame_samples, n);
        const int64_t start = hop;  // frame 1
        const int64_t total = start + n + frame_samples - 1;
        const std::vector<int64_t> completed = FramesCompleted(total, n, frame_samples, hop);
        ASSERT_FALSE(completed.empty());
        ASSERT_EQ(completed.front() * hop, start);
        EXPECT_TRUE(ring::FrameReadable(start, frame_samples, total, static_cast<int32_t>(capacity)));
        EXPECT_FALSE(ring::FrameReadable(start, frame_samples, total, static_cast<int32_t>(capacity - 1)));
      }
    }
  }
}

// Blocks of one fixed size: the span the completed frames need, maximised over a stream long
// enough to meet every alignment, is exactly CapacityForFixedBlocks; and the ring of that
// capacity reads every one of them back.
TEST(SampleRing, CapacityForFixedBlocksIsExactAndSuffices) {
  constexpr int kChannels = 1;
  std::mt19937 rng(7);
  for (int32_t frame_samples = 1; frame_samples <= 8; ++frame_samples) {
    for (int32_t hop = 1; hop <= 10; ++hop) {
      for (int32_t n = 1; n <= 11; ++n) {
        const auto capacity = static_cast<int32_t>(ring::CapacityForFixedBlocks(frame_samples, hop, n));
        ASSERT_GE(capacity, frame_samples);
        Model model(kChannels, capacity);
        int64_t widest = 0;
        const int blocks = 2 * (frame_samples + hop * n) / n + 8;  // past every residue
        for (int b = 0; b < blocks; ++b) {
          model.Append(RandomBlock(kChannels, n, rng), n);
          for (int64_t f : FramesCompleted(model.total(), n, frame_samples, hop)) {
            widest = std::max(widest, model.total() - f * hop);
            ASSERT_EQ(model.ReadRing(ring::FrameFirst(f, hop, capacity), frame_samples),
                      model.ReadStream(f * hop, frame_samples))
                << "F " << frame_samples << " H " << hop << " n " << n << " frame " << f;
          }
        }
        EXPECT_EQ(widest, capacity) << "F " << frame_samples << " H " << hop << " n " << n;
      }
    }
  }
  EXPECT_EQ(ring::CapacityForFixedBlocks(4096, 2048, 2048), 4096);  // a 50 % hop: one frame
}

TEST(SampleRing, ABlockLongerThanTheRingKeepsItsLastSamplesAndWritesEachIndexOnce) {
  for (int32_t capacity = 1; capacity <= 9; ++capacity) {
    for (int64_t total = 0; total < 2 * capacity; ++total) {
      for (int32_t n = 1; n <= 3 * capacity; ++n) {
        const ring::AppendPlan p = ring::PlanAppend(total, n, capacity);
        ASSERT_EQ(p.count, std::min(n, capacity));
        ASSERT_EQ(p.source_first, n - p.count);
        std::vector<int> writes(static_cast<std::size_t>(capacity), 0);
        for (int32_t i = 0; i < p.count; ++i) {
          const int32_t index = ring::Wrap(p.write_first, i, capacity);
          ASSERT_EQ(index, (total + p.source_first + i) % capacity);  // stream sample t at t mod capacity
          ++writes[static_cast<std::size_t>(index)];
        }
        for (int w : writes) ASSERT_LE(w, 1);
      }
    }
  }
}

// What GpuTdoaEstimator does: whole frames from a framer of random hop (some larger than the
// frame: gaps), the new samples found by NewSampleCount, a ring of F, the newest frame read
// back. Now and then a frame is altered in its overlap (as despiking does) or re-sent whole.
TEST(SampleRing, EstimatorJobsReadBackEveryFrameBitForBit) {
  constexpr int kChannels = 3;
  std::mt19937 rng(42);
  std::uniform_real_distribution<float> value(-1.0f, 1.0f);
  std::uniform_int_distribution<int> coin(0, 9);
  int reused = 0, frames = 0, overlapping = 0;
  for (int32_t frame_samples = 1; frame_samples <= 12; ++frame_samples) {
    for (int32_t hop = 1; hop <= 14; ++hop) {
      const int32_t capacity = frame_samples;
      std::vector<float> ring(static_cast<std::size_t>(kChannels) * capacity);
      std::vector<std::vector<float>> stream(kChannels);
      std::vector<float> previous;
      int64_t total = 0;  // samples the ring has taken
      int hint = 0;
      for (int f = 0; f < 30; ++f) {
        const std::size_t end = static_cast<std::size_t>(f) * hop + frame_samples;
        for (auto& row : stream) {
          while (row.size() < end) row.push_back(value(rng));
        }
        std::vector<float> frame;
        for (const auto& row : stream) frame.insert(frame.end(), row.end() - frame_samples, row.end());
        if (coin(rng) == 0) frame[static_cast<std::size_t>(coin(rng)) % frame.size()] *= 0.5f;  // despiked
        int32_t fresh = frame_samples;
        if (!previous.empty() && coin(rng) != 0) {
          fresh = NewSampleCount(previous.data(), frame.data(), kChannels, frame_samples, hint);
          hint = fresh;
        }
        reused += fresh < frame_samples;
        overlapping += f > 0 && hop < frame_samples;
        const ring::RingJobPlan p = ring::PlanRingJob(total, capacity, frame_samples, fresh);
        for (int c = 0; c < kChannels; ++c) {
          for (int32_t i = 0; i < p.append.count; ++i) {
            ring[static_cast<std::size_t>(c) * capacity + ring::Wrap(p.append.write_first, i, capacity)] =
                frame[static_cast<std::size_t>(c) * frame_samples + p.append.source_first + i];
          }
        }
        total += fresh;
        std::vector<float> read;
        for (int c = 0; c < kChannels; ++c) {
          for (int32_t i = 0; i < frame_samples; ++i) {
            read.push_back(ring[static_cast<std::size_t>(c) * capacity + ring::Wrap(p.frame_first, i, capacity)]);
          }
        }
        ASSERT_EQ(0, std::memcmp(read.data(), frame.data(), sizeof(float) * frame.size()))
            << "F " << frame_samples << " H " << hop << " frame " << f << " new " << fresh;
        previous = frame;
        ++frames;
      }
    }
  }
  EXPECT_GT(frames, 5000);
  // The overlap was found for most frames that had one (the others were altered or re-sent).
  EXPECT_GT(reused, overlapping * 2 / 3);
}

std::vector<float> Frames(const std::vector<float>& stream_row, int channels, int start, int frame_samples) {
  std::vector<float> frame;
  for (int c = 0; c < channels; ++c) {
    frame.insert(frame.end(), stream_row.begin() + start + c * 1000,
                 stream_row.begin() + start + c * 1000 + frame_samples);
  }
  return frame;
}

TEST(FrameOverlap, FindsTheHopOfAFramerWithAndWithoutTheHint) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> value(-1.0f, 1.0f);
  std::vector<float> stream(4000);
  for (float& v : stream) v = value(rng);
  for (int hop : {1, 7, 32, 64, 127}) {
    const std::vector<float> a = Frames(stream, 2, 0, 128), b = Frames(stream, 2, hop, 128);
    EXPECT_EQ(NewSampleCount(a.data(), b.data(), 2, 128, 0), hop);
    EXPECT_EQ(NewSampleCount(a.data(), b.data(), 2, 128, hop), hop);
    EXPECT_EQ(NewSampleCount(a.data(), b.data(), 2, 128, hop + 1), hop);  // a stale hint is refuted
  }
  const std::vector<float> a = Frames(stream, 2, 0, 128), gap = Frames(stream, 2, 200, 128);
  EXPECT_EQ(NewSampleCount(a.data(), gap.data(), 2, 128, 64), 128);  // no overlap: the whole frame
}

TEST(FrameOverlap, ADifferenceInAnyChannelOrSignBitRefusesTheShift) {
  std::vector<float> stream(4000);
  std::iota(stream.begin(), stream.end(), 1.0f);
  const std::vector<float> a = Frames(stream, 3, 0, 64);
  std::vector<float> b = Frames(stream, 3, 16, 64);
  ASSERT_EQ(NewSampleCount(a.data(), b.data(), 3, 64, 16), 16);
  b[2 * 64 + 5] += 1.0f;  // channel 2, inside the overlap (a despiked sample)
  EXPECT_EQ(NewSampleCount(a.data(), b.data(), 3, 64, 16), 64);
  std::vector<float> zeros(3 * 64, 0.0f), negative_zero = zeros;
  negative_zero[64 + 3] = -0.0f;  // == 0.0f, other bits
  EXPECT_EQ(NewSampleCount(zeros.data(), zeros.data(), 3, 64, 16), 16);
  EXPECT_NE(NewSampleCount(zeros.data(), negative_zero.data(), 3, 64, 16), 16);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  std::vector<float> with_nan = Frames(stream, 3, 0, 64), next = Frames(stream, 3, 16, 64);
  with_nan[40] = nan;  // shifts to next[24]
  next[24] = nan;
  EXPECT_EQ(NewSampleCount(with_nan.data(), next.data(), 3, 64, 16), 16);  // same bits reuse
}

// A constant signal that changes only in its last sample matches every pre-screen: the
// search stops after kMaxFullCompares full passes and sends the whole frame.
TEST(FrameOverlap, APathologicalStreamCostsABoundedSearch) {
  constexpr int kFrame = 256;
  std::vector<float> a(2 * kFrame, 1.0f), b(2 * kFrame, 1.0f);
  b[kFrame - 1] = 2.0f;
  b[2 * kFrame - 1] = 2.0f;
  EXPECT_EQ(NewSampleCount(a.data(), b.data(), 2, kFrame, 0), 1);  // shift 1 does match
  a[kFrame - 1] = 3.0f;  // now nothing small matches; shifts 1..4 are compared in full
  a[kFrame - 2] = 3.0f;
  a[kFrame - 3] = 3.0f;
  a[kFrame - 4] = 3.0f;
  EXPECT_EQ(NewSampleCount(a.data(), b.data(), 2, kFrame, 0), kFrame);
}

}  // namespace
}  // namespace localizer::gpu
