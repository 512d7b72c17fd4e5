#include "clients/io/raw_pcm.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <bit>
#include <cerrno>
#include <cmath>
#include <cstring>

namespace localizer::io {

namespace {

// libsndfile's integer-to-float factors (1 / 2^(bits - 1)); exact powers of two, so the
// multiply equals the division and matches libsndfile bit for bit.
constexpr float kS16Scale = 1.0f / 32768.0f;
constexpr float kS32Scale = 1.0f / 2147483648.0f;

// Little-endian assembly from bytes, whatever the host's byte order.
uint32_t Le32(const unsigned char* p) {
  return static_cast<uint32_t>(p[0]) | static_cast<uint32_t>(p[1]) << 8 | static_cast<uint32_t>(p[2]) << 16 |
         static_cast<uint32_t>(p[3]) << 24;
}
int16_t Le16(const unsigned char* p) { return static_cast<int16_t>(static_cast<uint16_t>(p[0] | p[1] << 8)); }

std::string ErrnoText() { return std::strerror(errno); }

}  // namespace

StatusOr<RawPcmFormat> ParseRawPcmFormat(const std::string& name) {
  for (RawPcmFormat f : {RawPcmFormat::kS16le, RawPcmFormat::kS32le, RawPcmFormat::kF32le}) {
    if (name == RawPcmFormatName(f)) return f;
  }
  return InvalidArgument("unknown raw PCM format '" + name + "'; expected s16le, s32le or f32le");
}

const char* RawPcmFormatName(RawPcmFormat format) {
  switch (format) {
    case RawPcmFormat::kS16le:
      return "s16le";
    case RawPcmFormat::kS32le:
      return "s32le";
    case RawPcmFormat::kF32le:
      return "f32le";
  }
  return "?";
}

int RawPcmBytesPerSample(RawPcmFormat format) { return format == RawPcmFormat::kS16le ? 2 : 4; }

Status RawPcmOptions::Validate() const {
  if (path.empty()) return InvalidArgument("raw PCM path is empty (use - for standard input)");
  if (channel_count < 1 || channel_count > kMaxRawPcmChannels) {
    return InvalidArgument("raw PCM channel_count is " + std::to_string(channel_count) + ", must be in [1, " +
                           std::to_string(kMaxRawPcmChannels) + "]");
  }
  if (!(std::isfinite(sample_rate_hz) && sample_rate_hz > 0.0)) {
    return InvalidArgument("raw PCM sample_rate_hz is " + std::to_string(sample_rate_hz) + ", must be > 0");
  }
  return Status::Ok();
}

StatusOr<std::unique_ptr<RawPcmStream>> RawPcmStream::Open(const RawPcmOptions& options) {
  LOCALIZER_RETURN_IF_ERROR(options.Validate());
  std::unique_ptr<RawPcmStream> stream(new RawPcmStream(options));
  if (options.path == "-") {
    stream->fd_ = STDIN_FILENO;
  } else {
    stream->fd_ = ::open(options.path.c_str(), O_RDONLY | O_CLOEXEC);
    if (stream->fd_ < 0) {
      if (errno == ENOENT) return NotFound(options.path + ": no such file");
      return InvalidArgument(options.path + ": cannot open (" + ErrnoText() + ")");
    }
    stream->owns_fd_ = true;
  }
  struct stat info {};
  if (::fstat(stream->fd_, &info) != 0) {
    return InvalidArgument(stream->Describe() + ": cannot stat (" + ErrnoText() + ")");
  }
  if (S_ISDIR(info.st_mode)) return InvalidArgument(stream->Describe() + ": is a directory");
  if (S_ISREG(info.st_mode)) {
    // What is left from the current offset (stdin redirected from a file may be part read).
    const off_t offset = ::lseek(stream->fd_, 0, SEEK_CUR);
    const int64_t bytes = static_cast<int64_t>(info.st_size) - (offset > 0 ? offset : 0);
    const int64_t leftover = bytes % stream->frame_bytes();
    if (leftover != 0) return InvalidArgument(stream->RemnantMessage(leftover));
    stream->total_frames_ = bytes / stream->frame_bytes();
  }
  return stream;
}

RawPcmStream::~RawPcmStream() {
  if (owns_fd_ && fd_ >= 0) ::close(fd_);
}

std::string RawPcmStream::Describe() const { return options_.path == "-" ? "stdin (--raw -)" : options_.path; }

int64_t RawPcmStream::frame_bytes() const {
  return static_cast<int64_t>(options_.channel_count) * RawPcmBytesPerSample(options_.format);
}

std::string RawPcmStream::RemnantMessage(int64_t leftover_bytes) const {
  return Describe() + ": " + std::to_string(leftover_bytes) + " byte(s) left over at the end, less than a frame (" +
         std::to_string(options_.channel_count) + " channels x " +
         std::to_string(RawPcmBytesPerSample(options_.format)) + " bytes of " + RawPcmFormatName(options_.format) +
         " = " + std::to_string(frame_bytes()) + " bytes), after " + std::to_string(frames_read_) +
         " whole frames: check --channels and --raw-format against the producer, or whether it was cut off "
         "mid-frame";
}

StatusOr<int64_t> RawPcmStream::Read(int64_t max_frames, std::vector<float>* channel_major) {
  if (max_frames <= 0) return InvalidArgument("max_frames is " + std::to_string(max_frames));
  if (!pending_.ok()) {
    channel_major->clear();
    return pending_;
  }
  const size_t wanted = static_cast<size_t>(max_frames) * static_cast<size_t>(frame_bytes());
  raw_.resize(wanted);
  size_t got = 0;
  // A pipe delivers what the producer has written so far; keep reading until the block is
  // full or the input ends, so that blocks (hence estimates) do not depend on pipe timing.
  while (got < wanted && !at_end_) {
    const ssize_t n = ::read(fd_, raw_.data() + got, wanted - got);
    if (n > 0) {
      got += static_cast<size_t>(n);
    } else if (n == 0) {
      at_end_ = true;
    } else if (errno != EINTR) {
      return InvalidArgument(Describe() + ": read failed after " + std::to_string(frames_read_) + " frames (" +
                             ErrnoText() + ")");
    }
  }
  const int64_t frames = static_cast<int64_t>(got) / frame_bytes();
  const int64_t leftover = static_cast<int64_t>(got) % frame_bytes();
  channel_major->resize(static_cast<size_t>(frames) * options_.channel_count);
  ConvertInterleavedPcm(options_.format, raw_.data(), frames, options_.channel_count, channel_major->data());
  frames_read_ += frames;
  if (leftover != 0) {
    pending_ = InvalidArgument(RemnantMessage(leftover));
    if (frames == 0) return pending_;
  }
  return frames;
}

void ConvertInterleavedPcm(RawPcmFormat format, const unsigned char* interleaved, int64_t frames, int channel_count,
                           float* channel_major) {
  const int bytes = RawPcmBytesPerSample(format);
  for (int64_t n = 0; n < frames; ++n) {
    for (int c = 0; c < channel_count; ++c) {
      const unsigned char* p = interleaved + (n * channel_count + c) * bytes;
      float v = 0.0f;
      switch (format) {
        case RawPcmFormat::kS16le:
          v = static_cast<float>(Le16(p)) * kS16Scale;
          break;
        case RawPcmFormat::kS32le:
          v = static_cast<float>(static_cast<int32_t>(Le32(p))) * kS32Scale;
          break;
        case RawPcmFormat::kF32le:
          v = std::bit_cast<float>(Le32(p));
          break;
      }
      channel_major[c * frames + n] = v;
    }
  }
}

}  // namespace localizer::io
