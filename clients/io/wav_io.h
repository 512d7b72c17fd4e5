// WAV files in and out, through libsndfile.
//
// Sample scaling. Every reader returns float32 with full scale = 1.0: libsndfile divides
// integer PCM by 2^(bits - 1) (int16 by 32768, int24 by 8388608, int32 by 2147483648), so
// the most negative code reads as exactly -1.0 and the most positive as 1 - 2^(1 - bits).
// Float WAV files are returned as stored (no clipping, no rescaling; values may exceed 1).
//
// Inputs. A recording is either one multichannel file (channel k = sensor k) or a set of
// mono files, one per sensor, in sensor order. A set must share one sample rate. Files of a
// set may differ slightly in length (separate recorders stop a few samples apart; the XAV
// hydrophone files differ by 230 samples): the set is truncated to its shortest file and a
// warning says so. Lengths differing by more than 1 s are an error, because they point to
// files from different recordings rather than recorders stopping apart.
//
// Errors: NOT_FOUND when a file does not exist; INVALID_ARGUMENT naming the file for
// anything libsndfile cannot read and for inconsistent sets. Not thread-safe per object.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "clients/io/sample_stream.h"
#include "engine/core/status.h"

namespace localizer::io {

// A whole recording in memory.
struct Recording {
  double sample_rate_hz = 0.0;
  int channel_count = 0;
  int64_t frames = 0;          // samples per channel
  std::vector<float> samples;  // channel-major: samples[c * frames + n]

  const float* channel(int c) const { return samples.data() + c * frames; }
};

// Largest length difference tolerated within a set of mono files.
inline constexpr double kMaxSetLengthMismatchS = 1.0;

// Reads a multichannel file, or a set of mono files in chunks, so that long recordings
// never need to sit in memory at once. Movable, not copyable.
class WavStream final : public SampleStream {
 public:
  // `paths`: one file of any channel count, or several mono files (one per sensor).
  static StatusOr<WavStream> Open(const std::vector<std::string>& paths);

  WavStream(WavStream&&) noexcept;
  WavStream& operator=(WavStream&&) noexcept;
  ~WavStream() override;

  double sample_rate_hz() const override { return sample_rate_hz_; }
  int channel_count() const override { return channel_count_; }
  int64_t total_frames() const override { return total_frames_; }  // after truncating a set
  int64_t frames_read() const { return frames_read_; }
  // Empty, or a note that a set was truncated to its shortest file.
  const std::string& warning() const { return warning_; }
  // "signals.wav" or "a.wav + 5 more": for messages.
  std::string Describe() const override;
  std::string RateOrigin() const override { return "the WAV header's rate"; }

  // Reads up to `max_frames` per channel, resizes `channel_major` to channel_count * n and
  // fills it channel-major (chunk sample i of channel c at [c * n + i]); returns n, which is
  // 0 only at the end of the recording.
  StatusOr<int64_t> Read(int64_t max_frames, std::vector<float>* channel_major) override;

 private:
  struct File;
  WavStream() = default;
  Status ReadInterleaved(int64_t frames, std::vector<float>* channel_major);
  Status ReadMonoSet(int64_t frames, std::vector<float>* channel_major);

  std::vector<File> files_;
  std::vector<float> interleaved_;  // reused buffer for multichannel files
  double sample_rate_hz_ = 0.0;
  int channel_count_ = 0;
  int64_t total_frames_ = 0;
  int64_t frames_read_ = 0;
  std::string warning_;
};

// One file, whole.
StatusOr<Recording> ReadWav(const std::string& path);
// One multichannel file or several mono files (see above), whole. `warning` (optional)
// receives the truncation note, or is cleared.
StatusOr<Recording> ReadWavSet(const std::vector<std::string>& paths, std::string* warning);
// Writes float32 WAV, channel k = sensor k. The sample rate must be a positive integer.
Status WriteWavFloat(const std::string& path, const Recording& recording);
// The same from channel-major samples held elsewhere (channel_count * frames values).
Status WriteWavFloat(const std::string& path, double sample_rate_hz, int channel_count, int64_t frames,
                     const float* channel_major);

}  // namespace localizer::io
