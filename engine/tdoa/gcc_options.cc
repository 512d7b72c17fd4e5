// GccPhatEstimator's names and options: weighting names both ways, GccOptions::Validate.
#include <cmath>
#include <cstdio>
#include <string>

#include "engine/tdoa/gcc_phat_impl.h"

namespace localizer::engine {
namespace {

constexpr int kMinFrameSamples = 64;
constexpr int kMaxFrameSamples = 1 << 20;

std::string Value(double v) {
  char text[32];
  std::snprintf(text, sizeof text, "%g", v);
  return text;
}

Status BadOption(const char* field, const std::string& value, const std::string& rule) {
  return InvalidArgument(std::string("GccOptions.") + field + " is " + value + "; " + rule);
}
Status BadOption(const char* field, double value, const std::string& rule) {
  return BadOption(field, Value(value), rule);
}
Status BadOption(const char* field, int value, const std::string& rule) {
  return BadOption(field, std::to_string(value), rule);
}

}  // namespace

StatusOr<Weighting> ParseWeighting(const std::string& name) {
  if (name == "phat") return Weighting::kPhat;
  if (name == "phat-beta") return Weighting::kPhatBeta;
  if (name == "scot") return Weighting::kScot;
  if (name == "cc") return Weighting::kCc;
  if (name == "phat-coherence") return Weighting::kPhatCoherence;
  if (name == "phat-share") return Weighting::kPhatShare;
  return InvalidArgument("weighting \"" + name +
                         "\" is not one of \"phat\", \"phat-beta\", \"scot\", \"cc\", "
                         "\"phat-coherence\", \"phat-share\"");
}

const char* WeightingName(Weighting w) {
  switch (w) {
    case Weighting::kPhat:
      return "phat";
    case Weighting::kPhatBeta:
      return "phat-beta";
    case Weighting::kScot:
      return "scot";
    case Weighting::kCc:
      return "cc";
    case Weighting::kPhatCoherence:
      return "phat-coherence";
    case Weighting::kPhatShare:
      return "phat-share";
  }
  return "unknown";
}

Status GccOptions::Validate() const {
  if (frame_samples < kMinFrameSamples || frame_samples > kMaxFrameSamples) {
    return BadOption("frame_samples", frame_samples,
                     "must be in [" + std::to_string(kMinFrameSamples) + ", " + std::to_string(kMaxFrameSamples) + "]");
  }
  if (!(sample_rate_hz > 0.0) || !std::isfinite(sample_rate_hz)) {
    return BadOption("sample_rate_hz", sample_rate_hz, "must be positive and finite");
  }
  const double nyquist_hz = 0.5 * sample_rate_hz;
  if (!(band_low_hz >= 0.0) || !(band_low_hz < nyquist_hz)) {
    return BadOption("band_low_hz", band_low_hz, "must be in [0, sample_rate_hz / 2 = " + Value(nyquist_hz) + ")");
  }
  if (!(band_high_hz >= 0.0) || !(band_high_hz <= nyquist_hz)) {
    return BadOption("band_high_hz", band_high_hz,
                     "must be 0 (up to Nyquist) or in (band_low_hz, sample_rate_hz / 2 = " + Value(nyquist_hz) + "]");
  }
  if (band_high_hz > 0.0 && !(band_high_hz > band_low_hz)) {
    return BadOption("band_high_hz", band_high_hz, "must exceed band_low_hz = " + Value(band_low_hz));
  }
  if (!(phat_beta >= 0.0 && phat_beta <= 1.0)) {
    return BadOption("phat_beta", phat_beta, "must be in [0, 1]");
  }
  if (!(taper_fraction >= 0.0 && taper_fraction <= 1.0)) {
    return BadOption("taper_fraction", taper_fraction, "must be in [0, 1]");
  }
  if (lag_margin_samples < 0) {
    return BadOption("lag_margin_samples", lag_margin_samples, "must be >= 0");
  }
  if (max_candidates < 1 || max_candidates > kMaxCandidates) {
    return BadOption("max_candidates", max_candidates, "must be in [1, " + std::to_string(kMaxCandidates) + "]");
  }
  if (cross_pairs_max_sensors < 0 || cross_pairs_max_sensors > 16) {
    return BadOption("cross_pairs_max_sensors", cross_pairs_max_sensors, "must be in [0, 16]");
  }
  if (!(coherence_time_constant_frames >= 1.0) || !std::isfinite(coherence_time_constant_frames)) {
    return BadOption("coherence_time_constant_frames", coherence_time_constant_frames, "must be finite and >= 1");
  }
  if (coherence_smoothing_bins < 0 || coherence_smoothing_bins > 4096) {
    return BadOption("coherence_smoothing_bins", coherence_smoothing_bins, "must be in [0, 4096]");
  }
  if (coherence_warmup_frames < 1) {
    return BadOption("coherence_warmup_frames", coherence_warmup_frames, "must be >= 1");
  }
  return Status::Ok();
}

}  // namespace localizer::engine
