// Physics through the installed API: a consumer of find_package(localizer) builds an array,
// asks the TDOA model for a known source and GCC-PHAT for a known delay, and exits non-zero
// (printing what differed) unless both match.
//
// Array: sensor 0 at the origin and sensors 1, 2, 3 on the x, y and z axes, kSpacingM away
// (the engine needs four sensors off a plane). Sound speed 343 m/s.
//  1. Model: a source on the x axis at 10 m reaches sensor 1 (9.5 m away) kSpacingM / c
//     earlier than sensor 0, so pair (0, 1) is -kSpacingM / c; sensors 2 and 3 are
//     sqrt(10^2 + 0.5^2) away. Checked to 1e-12 s (rounding only).
//  2. GCC-PHAT: seeded white noise on sensor 0, and on sensor k the same noise delayed by
//     an integer number of samples (exact, no interpolation filter): x_k[n] = x_0[n - D_k].
//     The measured pair delays must equal D_k / fs within kToleranceSamples; the estimator's
//     sinc refinement is documented at ~0.002 sample rms on clean frames (gcc_phat.h), so
//     0.05 sample (1 us at 48 kHz) leaves room without hiding a wrong sign or a lost peak.
#include <cmath>
#include <cstdio>
#include <random>
#include <vector>

#include "engine/array/array_geometry.h"
#include "engine/tdoa/gcc_phat.h"

namespace {

using localizer::engine::ArrayGeometry;
using localizer::engine::GccOptions;
using localizer::engine::GccPhatEstimator;
using localizer::engine::Measurement;
using localizer::engine::Vec3;

constexpr double kSpacingM = 0.5;
constexpr double kSoundSpeedMps = 343.0;
constexpr double kSampleRateHz = 48000.0;
constexpr int kFrameSamples = 4096;
constexpr double kToleranceSamples = 0.05;

int failures = 0;

void Check(bool ok, const char* what, double got, double want) {
  std::printf("%s %s: got %.9g, want %.9g\n", ok ? "ok  " : "FAIL", what, got, want);
  if (!ok) ++failures;
}

}  // namespace

int main() {
  auto array = ArrayGeometry::Create(
      {Vec3(0, 0, 0), Vec3(kSpacingM, 0, 0), Vec3(0, kSpacingM, 0), Vec3(0, 0, kSpacingM)}, kSoundSpeedMps);
  if (!array.ok()) {
    std::printf("FAIL ArrayGeometry::Create: %s\n", array.status().ToString().c_str());
    return 1;
  }

  // 1. The TDOA model of a known source position.
  const Eigen::VectorXd tdoa_s = array->Tdoa(Vec3(10.0, 0.0, 0.0));
  const double off_axis_s = (std::sqrt(10.0 * 10.0 + kSpacingM * kSpacingM) - 10.0) / kSoundSpeedMps;
  Check(std::abs(tdoa_s[0] - (-kSpacingM / kSoundSpeedMps)) < 1e-12, "model pair (0,1) s", tdoa_s[0],
        -kSpacingM / kSoundSpeedMps);
  Check(std::abs(tdoa_s[1] - off_axis_s) < 1e-12, "model pair (0,2) s", tdoa_s[1], off_axis_s);
  Check(std::abs(tdoa_s[2] - off_axis_s) < 1e-12, "model pair (0,3) s", tdoa_s[2], off_axis_s);

  // 2. GCC-PHAT of delayed copies of seeded noise. |D_k| stays inside the pair's physical
  // window (0.5 m / 343 m/s = 70 samples at 48 kHz), with both signs.
  const int delay_samples[4] = {0, 23, -41, 66};
  const int lead = 128;  // noise before the frame, so that delayed copies have no zeros
  std::mt19937 rng(20240519);
  std::normal_distribution<float> normal(0.0f, 1.0f);
  std::vector<float> source(kFrameSamples + 2 * lead);
  for (float& v : source) v = normal(rng);
  std::vector<float> frame(4 * kFrameSamples);  // channel-major
  for (int k = 0; k < 4; ++k) {
    for (int n = 0; n < kFrameSamples; ++n) frame[k * kFrameSamples + n] = source[lead + n - delay_samples[k]];
  }
  GccOptions options;
  options.frame_samples = kFrameSamples;
  options.sample_rate_hz = kSampleRateHz;
  auto gcc = GccPhatEstimator::Create(*array, options);
  if (!gcc.ok()) {
    std::printf("FAIL GccPhatEstimator::Create: %s\n", gcc.status().ToString().c_str());
    return 1;
  }
  Measurement measurement;
  const auto status = (*gcc)->Estimate(frame.data(), kFrameSamples, 0.0, &measurement);
  if (!status.ok() || measurement.pairs.size() != 3) {
    std::printf("FAIL Estimate: %s, %zu pairs\n", status.ToString().c_str(), measurement.pairs.size());
    return 1;
  }
  for (int p = 0; p < 3; ++p) {
    const double want_s = delay_samples[p + 1] / kSampleRateHz;
    const double got_s = measurement.pairs[p].delay_s;
    const char* names[3] = {"GCC-PHAT pair (0,1) s", "GCC-PHAT pair (0,2) s", "GCC-PHAT pair (0,3) s"};
    Check(std::abs(got_s - want_s) * kSampleRateHz <= kToleranceSamples, names[p], got_s, want_s);
  }
  std::printf("%s\n", failures == 0 ? "consumer: all checks passed" : "consumer: checks failed");
  return failures == 0 ? 0 : 1;
}
