#include "engine/tdoa/peak_interpolation.h"

namespace localizer::engine {

const char* PeakInterpolationName(PeakInterpolation method) {
  switch (method) {
    case PeakInterpolation::kParabolic:
      return "parabolic";
    case PeakInterpolation::kGaussian:
      return "gaussian";
    case PeakInterpolation::kSinc:
      return "sinc";
  }
  return "unknown";
}

double InterpolatePeak(PeakInterpolation method, std::span<const float, kPeakSamples> samples) {
  return InterpolatePeak(method, samples.data());
}

double SincReconstruct(std::span<const float, kPeakSamples> samples, double x) {
  return EvaluateSinc(samples.data(), x).value;
}

double SincCurvature(std::span<const float, kPeakSamples> samples, double x) {
  return EvaluateSinc(samples.data(), x).curvature;
}

}  // namespace localizer::engine
