// Headerless PCM in: `localizer-cli track --raw FILE|-` (docs/CLI.md, "Raw PCM"), so that a live
// capture or a converter can be piped straight in:
//     arecord -t raw -f S16_LE -c 4 -r 48000 | localizer-cli track --raw - --channels 4 ...
//     ffmpeg -i take.flac -f f32le - | localizer-cli track --raw - --raw-format f32le ...
//
// Layout: interleaved frames (channel 0, 1, ..., N-1 of sample 0, then of sample 1, ...;
// channel k = sensor k), little-endian, one of
//     s16le  signed 16-bit   sample = code / 32768          (-32768 reads as exactly -1.0)
//     s32le  signed 32-bit   sample = float(code) / 2^31     (code rounded to float first)
//     f32le  IEEE float32    sample as stored (no clipping; values may exceed 1)
// the scaling libsndfile applies to WAV files (wav_io.h), computed the same way (float
// multiply by an exact power of two), so a raw copy of a WAV file's samples gives the same
// floats bit for bit and hence the same estimates. Non-finite f32 values are passed on, as
// the WAV reader passes them on: the session rejects the block naming channel and sample.
//
// Streaming: Read() pulls one block's bytes with read(2), waiting on a pipe until the block
// is full or the input ends, and converts them; memory is one block however long the input.
// Standard input is never read ahead of the blocks asked for, and never closed.
//
// Length: a regular file (also one redirected to stdin) gives total_frames() from its size;
// a pipe gives 0 (unknown). Trailing bytes that do not make a whole frame are an ERROR
// (INVALID_ARGUMENT saying how many bytes were left over and the frame size): the input then
// disagrees with the stated channel count or format, which scrambles channel order, or the
// producer was cut off mid-frame; the reader cannot tell which, so it does not guess. A
// regular file is checked at Open, before anything is read; a pipe when it ends, after the
// whole frames before the remnant have been returned (the next Read reports it).
//
// Errors: NOT_FOUND for a missing file; INVALID_ARGUMENT for bad options (naming the field),
// an unreadable input, a failed read and the remnant above. Not thread-safe per object.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "clients/io/sample_stream.h"
#include "engine/core/status.h"

namespace localizer::io {

enum class RawPcmFormat { kS16le, kS32le, kF32le };

// "s16le", "s32le", "f32le"; anything else is INVALID_ARGUMENT listing them.
StatusOr<RawPcmFormat> ParseRawPcmFormat(const std::string& name);
const char* RawPcmFormatName(RawPcmFormat format);
int RawPcmBytesPerSample(RawPcmFormat format);

// `frames` interleaved little-endian frames of `channel_count` samples at `interleaved` ->
// channel-major floats at `channel_major` (channel c's sample i at [c * frames + i]), scaled
// as above. Shared with live capture (alsa_capture.h), so that the same codes give the same
// floats, hence the same estimates, whether they come from a file, a pipe or a device.
void ConvertInterleavedPcm(RawPcmFormat format, const unsigned char* interleaved, int64_t frames, int channel_count,
                           float* channel_major);

// Largest channel count accepted; far above any array, it keeps frame sizes small.
inline constexpr int kMaxRawPcmChannels = 4096;

struct RawPcmOptions {
  std::string path;                            // a file, or "-" for standard input
  RawPcmFormat format = RawPcmFormat::kS16le;  // --raw-format
  int channel_count = 0;                       // --channels: interleaved channels per frame, [1, kMaxRawPcmChannels]
  double sample_rate_hz = 0.0;                 // --sample-rate: per channel, > 0, finite

  Status Validate() const;  // INVALID_ARGUMENT naming the field and value
};

class RawPcmStream final : public SampleStream {
 public:
  static StatusOr<std::unique_ptr<RawPcmStream>> Open(const RawPcmOptions& options);
  ~RawPcmStream() override;  // closes a file it opened; standard input stays open
  RawPcmStream(const RawPcmStream&) = delete;
  RawPcmStream& operator=(const RawPcmStream&) = delete;

  double sample_rate_hz() const override { return options_.sample_rate_hz; }
  int channel_count() const override { return options_.channel_count; }
  int64_t total_frames() const override { return total_frames_; }  // 0: a pipe, unknown
  int64_t frames_read() const { return frames_read_; }
  // "stdin (--raw -)" or the file's path.
  std::string Describe() const override;
  std::string RateOrigin() const override { return "--sample-rate"; }
  StatusOr<int64_t> Read(int64_t max_frames, std::vector<float>* channel_major) override;

 private:
  explicit RawPcmStream(const RawPcmOptions& options) : options_(options) {}
  int64_t frame_bytes() const;
  std::string RemnantMessage(int64_t leftover_bytes) const;

  RawPcmOptions options_;
  int fd_ = -1;
  bool owns_fd_ = false;  // false for standard input
  int64_t total_frames_ = 0;
  int64_t frames_read_ = 0;
  bool at_end_ = false;
  Status pending_;                  // the remnant error, reported by the Read after the last frames
  std::vector<unsigned char> raw_;  // one block of input bytes, reused
};

}  // namespace localizer::io
