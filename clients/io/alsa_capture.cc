// AlsaCaptureStream on libasound2 (alsa_capture.h says what it does and why); built when
// CMake finds ALSA, else alsa_capture_unavailable.cc stands in.
#include "clients/io/alsa_capture.h"

#include <alsa/asoundlib.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdarg>
#include <cstdint>
#include <cstdio>
#include <mutex>

namespace localizer::io {

namespace {

// A wait slice: how late a stop request or the no-data check can be noticed.
constexpr int kWaitSliceMs = 100;

double MonotonicSeconds() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

// ALSA prints its own diagnostics to stderr ("ALSA lib pcm.c:2666:(snd_pcm_open_noupdate)
// Unknown PCM nosuch"); they are kept instead and appended to our message, so that the user
// sees one message naming the device. One process-wide handler: ALSA has no per-PCM one.
std::mutex alsa_message_mutex;
std::string alsa_last_message;

void KeepAlsaMessage(const char* /*file*/, int /*line*/, const char* /*function*/, int /*err*/, const char* fmt, ...) {
  char text[512];
  va_list args;
  va_start(args, fmt);
  std::vsnprintf(text, sizeof(text), fmt, args);
  va_end(args);
  const std::lock_guard<std::mutex> lock(alsa_message_mutex);
  alsa_last_message = text;
}

void InstallAlsaMessageHandler() {
  static std::once_flag once;
  std::call_once(once, [] { snd_lib_error_set_handler(&KeepAlsaMessage); });
}

std::string TakeAlsaMessage() {
  const std::lock_guard<std::mutex> lock(alsa_message_mutex);
  std::string message;
  message.swap(alsa_last_message);
  return message;
}

snd_pcm_format_t AlsaFormatOf(RawPcmFormat format) {
  switch (format) {
    case RawPcmFormat::kS16le:
      return SND_PCM_FORMAT_S16_LE;
    case RawPcmFormat::kS32le:
      return SND_PCM_FORMAT_S32_LE;
    case RawPcmFormat::kF32le:
      return SND_PCM_FORMAT_FLOAT_LE;
  }
  return SND_PCM_FORMAT_UNKNOWN;
}

const char* AlsaFormatName(RawPcmFormat format) { return snd_pcm_format_name(AlsaFormatOf(format)); }

// Highest resolution first: a device's native format is usually S32_LE (24 bits in 32) or
// S16_LE; FLOAT_LE comes from plugins. Every one becomes float32 for the tracker anyway.
constexpr RawPcmFormat kBestFirst[] = {RawPcmFormat::kS32le, RawPcmFormat::kF32le, RawPcmFormat::kS16le};

RawPcmFormat RawFormatOf(AlsaSampleFormat format) {
  switch (format) {
    case AlsaSampleFormat::kS16:
      return RawPcmFormat::kS16le;
    case AlsaSampleFormat::kS32:
      return RawPcmFormat::kS32le;
    case AlsaSampleFormat::kF32:
    case AlsaSampleFormat::kBest:
      break;
  }
  return RawPcmFormat::kF32le;
}

}  // namespace

bool AlsaCaptureAvailable() { return true; }

AlsaCaptureStream::AlsaCaptureStream(const AlsaCaptureOptions& options) : options_(options) {}

AlsaCaptureStream::~AlsaCaptureStream() {
  if (pcm_ != nullptr) snd_pcm_close(pcm_);
}

std::string AlsaCaptureStream::Describe() const { return "ALSA device '" + options_.device + "'"; }

Status AlsaCaptureStream::Error(StatusCode code, const std::string& what, int alsa_error) const {
  std::string message = Describe() + ": " + what;
  if (alsa_error < 0) message += ": " + std::string(snd_strerror(alsa_error));
  const std::string alsa_message = TakeAlsaMessage();
  if (!alsa_message.empty()) message += " (ALSA: " + alsa_message + ")";
  return Status(code, message);
}

StatusOr<std::unique_ptr<AlsaCaptureStream>> AlsaCaptureStream::Open(const AlsaCaptureOptions& options) {
  LOCALIZER_RETURN_IF_ERROR(options.Validate());
  InstallAlsaMessageHandler();
  TakeAlsaMessage();
  std::unique_ptr<AlsaCaptureStream> stream(new AlsaCaptureStream(options));
  snd_pcm_t* pcm = nullptr;
  int err = 0;
  if (options.config_text.empty()) {
    err = snd_pcm_open(&pcm, options.device.c_str(), SND_PCM_STREAM_CAPTURE, SND_PCM_NONBLOCK);
  } else {
    // A configuration of the caller's own (tests define `file` and `null` plugin devices so
    // without a sound card): the device is looked up there, not in /usr/share/alsa.
    snd_config_t* config = nullptr;
    snd_input_t* input = nullptr;
    err = snd_config_top(&config);
    if (err >= 0) err = snd_input_buffer_open(&input, options.config_text.data(), options.config_text.size());
    if (err >= 0) err = snd_config_load(config, input);
    if (input != nullptr) snd_input_close(input);
    if (err < 0) {
      if (config != nullptr) snd_config_delete(config);
      return stream->Error(StatusCode::kInvalidArgument, "cannot parse the ALSA configuration text", err);
    }
    err = snd_pcm_open_lconf(&pcm, options.device.c_str(), SND_PCM_STREAM_CAPTURE, SND_PCM_NONBLOCK, config);
    snd_config_delete(config);  // the PCM keeps nothing of it
  }
  if (err < 0) {
    return stream->Error(err == -ENOENT ? StatusCode::kNotFound : StatusCode::kInvalidArgument,
                         "cannot open for capture", err);
  }
  stream->pcm_ = pcm;
  LOCALIZER_RETURN_IF_ERROR(stream->Configure());
  return stream;
}

StatusOr<std::unique_ptr<AlsaCaptureStream>> AlsaCaptureStream::Adopt(_snd_pcm* pcm,
                                                                      const AlsaCaptureOptions& options) {
  std::unique_ptr<AlsaCaptureStream> stream(new AlsaCaptureStream(options));
  stream->pcm_ = pcm;  // closed by the destructor, on error too
  LOCALIZER_RETURN_IF_ERROR(options.Validate());
  InstallAlsaMessageHandler();
  TakeAlsaMessage();
  if (snd_pcm_stream(pcm) != SND_PCM_STREAM_CAPTURE) {
    return stream->Error(StatusCode::kInvalidArgument, "is not a capture PCM", 0);
  }
  const int err = snd_pcm_nonblock(pcm, 1);
  if (err < 0) return stream->Error(StatusCode::kInvalidArgument, "cannot be made non-blocking", err);
  LOCALIZER_RETURN_IF_ERROR(stream->Configure());
  return stream;
}

Status AlsaCaptureStream::Configure() {
  snd_pcm_hw_params_t* hw = nullptr;
  snd_pcm_hw_params_alloca(&hw);
  int err = snd_pcm_hw_params_any(pcm_, hw);
  if (err < 0) return Error(StatusCode::kInvalidArgument, "cannot read what it offers", err);
  // Never resample behind the tracker's back: the rate must be the device's own.
  err = snd_pcm_hw_params_set_rate_resample(pcm_, hw, 0);
  if (err < 0) return Error(StatusCode::kInvalidArgument, "cannot turn ALSA's resampling off", err);
  err = snd_pcm_hw_params_set_access(pcm_, hw, SND_PCM_ACCESS_RW_INTERLEAVED);
  if (err < 0) return Error(StatusCode::kInvalidArgument, "does not offer interleaved read access", err);

  std::string offered;
  bool found = false;
  for (RawPcmFormat f : kBestFirst) {
    if (snd_pcm_hw_params_test_format(pcm_, hw, AlsaFormatOf(f)) == 0) {
      offered += (offered.empty() ? "" : ", ") + std::string(AlsaFormatName(f));
      const bool wanted = options_.format == AlsaSampleFormat::kBest || RawFormatOf(options_.format) == f;
      if (wanted && !found) {
        format_ = f;
        found = true;
      }
    }
  }
  if (!found) {
    const std::string asked = options_.format == AlsaSampleFormat::kBest
                                  ? "none of S32_LE, FLOAT_LE, S16_LE"
                                  : std::string(AlsaFormatName(RawFormatOf(options_.format)));
    return Error(StatusCode::kInvalidArgument,
                 "cannot deliver " + asked + " samples (of those it offers " + (offered.empty() ? "none" : offered) +
                     "; choose one with --alsa-format)",
                 0);
  }
  err = snd_pcm_hw_params_set_format(pcm_, hw, AlsaFormatOf(format_));
  if (err < 0) return Error(StatusCode::kInvalidArgument, std::string("cannot set ") + AlsaFormatName(format_), err);

  const auto channels = static_cast<unsigned>(options_.channel_count);
  if (snd_pcm_hw_params_test_channels(pcm_, hw, channels) != 0) {
    unsigned min_channels = 0;
    unsigned max_channels = 0;
    snd_pcm_hw_params_get_channels_min(hw, &min_channels);
    snd_pcm_hw_params_get_channels_max(hw, &max_channels);
    return Error(StatusCode::kInvalidArgument,
                 "cannot capture " + std::to_string(channels) + " channels (it offers " + std::to_string(min_channels) +
                     (max_channels != min_channels ? ".." + std::to_string(max_channels) : "") +
                     "); --channels must be what the device gives, channel k = sensor k",
                 0);
  }
  err = snd_pcm_hw_params_set_channels(pcm_, hw, channels);
  if (err < 0) return Error(StatusCode::kInvalidArgument, "cannot set " + std::to_string(channels) + " channels", err);

  const auto rate_hz = static_cast<unsigned>(options_.sample_rate_hz);
  if (snd_pcm_hw_params_test_rate(pcm_, hw, rate_hz, 0) != 0) {
    unsigned min_rate = 0;
    unsigned max_rate = 0;
    int dir = 0;
    snd_pcm_hw_params_get_rate_min(hw, &min_rate, &dir);
    snd_pcm_hw_params_get_rate_max(hw, &max_rate, &dir);
    return Error(StatusCode::kInvalidArgument,
                 "cannot capture at exactly " + std::to_string(rate_hz) + " Hz (it offers " + std::to_string(min_rate) +
                     (max_rate != min_rate ? ".." + std::to_string(max_rate) : "") + " Hz with " +
                     std::to_string(channels) +
                     " channels); localizer does not resample: give --sample-rate the device's rate",
                 0);
  }
  err = snd_pcm_hw_params_set_rate(pcm_, hw, rate_hz, 0);
  if (err < 0) return Error(StatusCode::kInvalidArgument, "cannot set " + std::to_string(rate_hz) + " Hz", err);

  // Period and buffer: asked for, the device rounds to what it can.
  auto period = static_cast<snd_pcm_uframes_t>(std::max(1.0, std::round(options_.period_s * options_.sample_rate_hz)));
  auto buffer = static_cast<snd_pcm_uframes_t>(std::max(2.0, std::round(options_.buffer_s * options_.sample_rate_hz)));
  int dir = 0;
  err = snd_pcm_hw_params_set_period_size_near(pcm_, hw, &period, &dir);
  if (err < 0)
    return Error(StatusCode::kInvalidArgument, "cannot set a period near " + std::to_string(period) + " frames", err);
  err = snd_pcm_hw_params_set_buffer_size_near(pcm_, hw, &buffer);
  if (err < 0)
    return Error(StatusCode::kInvalidArgument, "cannot set a buffer near " + std::to_string(buffer) + " frames", err);
  err = snd_pcm_hw_params(pcm_, hw);
  if (err < 0) return Error(StatusCode::kInvalidArgument, "cannot apply the hardware parameters", err);
  snd_pcm_hw_params_get_period_size(hw, &period, &dir);
  snd_pcm_hw_params_get_buffer_size(hw, &buffer);
  period_frames_ = static_cast<int64_t>(period);
  buffer_frames_ = static_cast<int64_t>(buffer);
  duration_frames_ = std::llround(options_.duration_s * options_.sample_rate_hz);
  return Status::Ok();
}

bool AlsaCaptureStream::stop_requested() const { return options_.stop != nullptr && options_.stop->load(); }

void AlsaCaptureStream::NoteRead() {
  const snd_pcm_sframes_t avail = snd_pcm_avail(pcm_);
  buffered_at_last_read_ = avail > 0 ? static_cast<int64_t>(avail) : 0;
  last_read_time_s_ = MonotonicSeconds();
}

StatusOr<int64_t> AlsaCaptureStream::Recover(int alsa_error) {
  const char* what = alsa_error == -ESTRPIPE ? "suspended" : "overrun";
  int err = snd_pcm_recover(pcm_, alsa_error, /*silent=*/1);
  if (err < 0) return Error(StatusCode::kUnavailable, std::string("cannot recover from an ") + what, err);
  err = snd_pcm_start(pcm_);
  if (err < 0) return Error(StatusCode::kUnavailable, std::string("cannot restart after an ") + what, err);
  // Lost: what the buffer held at the last read (dropped by the restart), and everything the
  // device would have captured from then until the restart.
  const double restart_s = MonotonicSeconds();
  const int64_t lost =
      buffered_at_last_read_ + std::llround(std::max(0.0, restart_s - last_read_time_s_) * options_.sample_rate_hz);
  last_read_time_s_ = restart_s;
  buffered_at_last_read_ = 0;
  ++overruns_;
  frames_lost_ += lost;
  return lost;
}

int64_t AlsaCaptureStream::RemainingFrames() const {
  if (duration_frames_ <= 0) return INT64_MAX;
  return std::max<int64_t>(0, duration_frames_ - frames_read_ - frames_lost_);
}

StatusOr<int64_t> AlsaCaptureStream::Read(int64_t max_frames, std::vector<float>* channel_major) {
  if (max_frames <= 0) return InvalidArgument("max_frames is " + std::to_string(max_frames));
  gap_before_last_read_ = 0;
  channel_major->clear();
  int64_t gap_before = gap_pending_;
  gap_pending_ = 0;
  if (!started_) {
    const int err = snd_pcm_start(pcm_);
    if (err < 0) return Error(StatusCode::kUnavailable, "cannot start capturing", err);
    started_ = true;
    last_read_time_s_ = MonotonicSeconds();
  }
  const int64_t frame_bytes = static_cast<int64_t>(options_.channel_count) * RawPcmBytesPerSample(format_);
  int64_t wanted = std::min(max_frames, RemainingFrames());
  raw_.resize(static_cast<size_t>(wanted * frame_bytes));
  int64_t got = 0;
  while (got < wanted && !ended_) {
    if (stop_requested()) {
      ended_ = true;
      break;
    }
    const auto ask = static_cast<snd_pcm_uframes_t>(std::min(wanted - got, buffer_frames_));
    const snd_pcm_sframes_t n = snd_pcm_readi(pcm_, raw_.data() + got * frame_bytes, ask);
    int err = 0;
    if (n > 0) {
      got += n;
      NoteRead();
      continue;
    }
    if (n == 0 || n == -EAGAIN) {
      if (MonotonicSeconds() - last_read_time_s_ >= options_.no_data_timeout_s) {
        return Error(StatusCode::kUnavailable,
                     "no samples from the device for " + std::to_string(options_.no_data_timeout_s) + " s (after " +
                         std::to_string(frames_read_ + got) + " frames)",
                     0);
      }
      err = snd_pcm_wait(pcm_, kWaitSliceMs);
      if (err >= 0 || err == -EINTR) continue;  // ready, a slice passed, or a signal: look again
    } else {
      err = static_cast<int>(n);
    }
    if (err == -EINTR) continue;
    if (err != -EPIPE && err != -ESTRPIPE) {
      return Error(StatusCode::kUnavailable, "read failed after " + std::to_string(frames_read_ + got) + " frames",
                   err);
    }
    auto lost = Recover(err);
    if (!lost.ok()) return lost.status();
    if (got > 0) {  // the block so far is whole; the loss comes before the next one
      gap_pending_ += *lost;
      break;
    }
    gap_before += *lost;
    wanted = std::min(wanted, RemainingFrames());
  }
  channel_major->resize(static_cast<size_t>(got) * options_.channel_count);
  ConvertInterleavedPcm(format_, raw_.data(), got, options_.channel_count, channel_major->data());
  frames_read_ += got;
  gap_before_last_read_ = got > 0 ? gap_before : 0;
  if (RemainingFrames() == 0) ended_ = true;
  return got;
}

}  // namespace localizer::io
