// What alsa_capture.h declares that needs no libasound: the options and the format names,
// built with or without ALSA so that the CLI parses and checks its flags either way.
#include <climits>
#include <cmath>

#include "clients/io/alsa_capture.h"

namespace localizer::io {

const char* const kAlsaUnavailableMessage = "built without ALSA (install libasound2-dev and configure again)";

StatusOr<AlsaSampleFormat> ParseAlsaSampleFormat(const std::string& name) {
  for (AlsaSampleFormat f :
       {AlsaSampleFormat::kBest, AlsaSampleFormat::kS16, AlsaSampleFormat::kS32, AlsaSampleFormat::kF32}) {
    if (name == AlsaSampleFormatName(f)) return f;
  }
  return InvalidArgument("unknown ALSA sample format '" + name + "'; expected s16, s32, f32 or best");
}

const char* AlsaSampleFormatName(AlsaSampleFormat format) {
  switch (format) {
    case AlsaSampleFormat::kBest:
      return "best";
    case AlsaSampleFormat::kS16:
      return "s16";
    case AlsaSampleFormat::kS32:
      return "s32";
    case AlsaSampleFormat::kF32:
      return "f32";
  }
  return "?";
}

namespace {

bool PositiveFinite(double v) { return std::isfinite(v) && v > 0.0; }

}  // namespace

Status AlsaCaptureOptions::Validate() const {
  if (device.empty()) return InvalidArgument("ALSA device name is empty");
  if (channel_count < 1 || channel_count > kMaxRawPcmChannels) {
    return InvalidArgument("ALSA channel_count is " + std::to_string(channel_count) + ", must be in [1, " +
                           std::to_string(kMaxRawPcmChannels) + "]");
  }
  // ALSA rates are whole hertz; a fractional rate would be rounded by the device, and the
  // tracker would then run at a rate the samples were not taken at.
  if (!PositiveFinite(sample_rate_hz) || sample_rate_hz != std::floor(sample_rate_hz) ||
      sample_rate_hz > static_cast<double>(UINT_MAX)) {
    return InvalidArgument("ALSA sample_rate_hz is " + std::to_string(sample_rate_hz) +
                           ", must be a whole number of Hz > 0");
  }
  if (!PositiveFinite(period_s))
    return InvalidArgument("ALSA period_s is " + std::to_string(period_s) + ", must be > 0");
  if (!(std::isfinite(buffer_s) && buffer_s >= 2.0 * period_s)) {
    return InvalidArgument("ALSA buffer_s is " + std::to_string(buffer_s) + ", must be at least two periods (" +
                           std::to_string(2.0 * period_s) + " s)");
  }
  if (!(std::isfinite(duration_s) && duration_s >= 0.0)) {
    return InvalidArgument("duration_s is " + std::to_string(duration_s) + ", must be >= 0 (0: until stopped)");
  }
  if (!PositiveFinite(no_data_timeout_s)) {
    return InvalidArgument("ALSA no_data_timeout_s is " + std::to_string(no_data_timeout_s) + ", must be > 0");
  }
  return Status::Ok();
}

}  // namespace localizer::io
