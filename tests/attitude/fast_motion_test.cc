// Inclination under fast motion (issue 22): a simulated sensor that tumbles while it is
// moved hard, so the accelerometer carries linear accelerations as large as gravity, and the
// study that prints it beside the three BROAD trials (6D inclination, 9D total).
//
// The simulated case (one draw per seed, std::mt19937_64): still for 5 s (a BROAD trial starts
// at rest), then, ramping in over 2 s, a body rate per axis that is the sum of two sinusoids
// (1-2.5 rad/s, 0.2-1.2 Hz; the truth integrates it, 16 steps per sample) and a world-frame
// linear acceleration per axis that is the sum of two sinusoids (3-8 m/s^2 times a scale, at
// random frequencies in a band: 0.5-1.5 Hz "swaying", a hand moving the sensor, or 2-5 Hz
// "shaking"). Sensor: 285.7 Hz (BROAD's rate), gyro noise 0.005 rad/s per sample, bias up to
// 0.01 rad/s and scale factor off by up to 0.5 % per axis; accelerometer noise 0.05 m/s^2 per
// sample, bias up to 0.05 m/s^2 per axis. No magnetometer. Scored from 10 s.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <map>
#include <random>
#include <string>
#include <vector>

#include "engine/attitude/attitude_error.h"
#include "engine/attitude/attitude_filter.h"
#include "tests/attitude/broad_trials.h"
#include "tests/attitude/estimate_dump.h"
#include "tests/attitude/options_from_environment.h"

namespace localizer::engine {
namespace {

constexpr double kDeg = M_PI / 180.0;
constexpr double kRateHz = 285.714;

struct FastCase {
  std::vector<Eigen::Quaterniond> truth;  // body -> world at each sample
  std::vector<ImuSample> samples;
};

// The tumbling, shaken sensor for `seed`: still for kStill_s, the motion ramping in over the
// next 2 s (as a BROAD trial starts at rest), duration_s of samples in all; linear_scale
// scales the shaking (1: the amplitudes above). The body rate per axis is a sum of two
// sinusoids (amplitudes 1-2.5 rad/s, 0.2-1.2 Hz); the truth integrates it exactly (16 steps
// per sample, midpoint rate), the gyro samples it.
constexpr double kStill_s = 5.0;
FastCase MakeFastCase(uint64_t seed, double duration_s, double linear_scale, double f_lo_hz, double f_hi_hz) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::normal_distribution<double> n(0.0, 1.0);
  double rate_amp[3][2], rate_freq[3][2], rate_phase[3][2], amp[3][2], freq[3][2], phase[3][2];
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 2; ++j) {
      rate_amp[i][j] = 1.0 + 1.5 * u(rng);
      rate_freq[i][j] = 0.2 + 1.0 * u(rng);
      rate_phase[i][j] = 2.0 * M_PI * u(rng);
      amp[i][j] = linear_scale * (3.0 + 5.0 * u(rng));
      freq[i][j] = f_lo_hz + (f_hi_hz - f_lo_hz) * u(rng);
      phase[i][j] = 2.0 * M_PI * u(rng);
    }
  }
  Eigen::Vector3d gyro_bias, gyro_scale, accel_bias;
  for (int i = 0; i < 3; ++i) {
    gyro_bias[i] = 0.01 * (2.0 * u(rng) - 1.0);
    gyro_scale[i] = 0.005 * (2.0 * u(rng) - 1.0);
    accel_bias[i] = 0.05 * (2.0 * u(rng) - 1.0);
  }
  // The study's knobs (ACCURACY.md): the gyro's scale and bias errors scaled (0: none).
  if (const char* k = std::getenv("ATT_SIM_GYRO_ERRORS")) {
    gyro_scale *= std::atof(k);
    gyro_bias *= std::atof(k);
  }
  const auto envelope = [](double t) {
    if (t < kStill_s) return 0.0;
    if (t > kStill_s + 2.0) return 1.0;
    return 0.5 - 0.5 * std::cos(M_PI * (t - kStill_s) / 2.0);
  };
  const auto rate = [&](double t) {
    Eigen::Vector3d w = Eigen::Vector3d::Zero();
    for (int i = 0; i < 3; ++i) {
      for (int j = 0; j < 2; ++j) w[i] += rate_amp[i][j] * std::sin(2.0 * M_PI * rate_freq[i][j] * t + rate_phase[i][j]);
    }
    return Eigen::Vector3d(envelope(t) * w);
  };
  FastCase c;
  const int count = static_cast<int>(duration_s * kRateHz);
  c.samples.reserve(count);
  c.truth.reserve(count);
  Eigen::Quaterniond q = Eigen::AngleAxisd(0.3, Eigen::Vector3d(1.0, 0.5, 0.2).normalized()) * Eigen::Quaterniond::Identity();
  constexpr int kSub = 16;
  for (int k = 0; k < count; ++k) {
    const double t = k / kRateHz;
    if (k > 0) {
      const double h = 1.0 / (kRateHz * kSub);
      for (int m = 0; m < kSub; ++m) {
        const Eigen::Vector3d w = rate(t - 1.0 / kRateHz + (m + 0.5) * h) * h;
        if (w.norm() > 0.0) q = (q * Eigen::Quaterniond(Eigen::AngleAxisd(w.norm(), w.normalized()))).normalized();
      }
    }
    Eigen::Vector3d a_lin;
    for (int i = 0; i < 3; ++i) {
      a_lin[i] = 0.0;
      for (int j = 0; j < 2; ++j) a_lin[i] += amp[i][j] * std::sin(2.0 * M_PI * freq[i][j] * t + phase[i][j]);
    }
    a_lin *= envelope(t);
    ImuSample s;
    s.t_s = t;
    const Eigen::Vector3d omega = rate(t);
    s.gyro_rps = omega + gyro_scale.cwiseProduct(omega) + gyro_bias + 0.005 * Eigen::Vector3d(n(rng), n(rng), n(rng));
    s.accel_mps2 = q.conjugate() * (a_lin + Eigen::Vector3d(0.0, 0.0, 9.81)) + accel_bias +
                   0.05 * Eigen::Vector3d(n(rng), n(rng), n(rng));
    s.mag_uT.setConstant(std::numeric_limits<double>::quiet_NaN());
    c.samples.push_back(s);
    c.truth.push_back(q);
  }
  return c;
}

// RMS inclination error (deg) over the samples with t >= from_s.
double InclinationRmsDeg(const FastCase& c, const AttitudeFilterOptions& options, double from_s) {
  auto filter = CreateAttitudeFilter(options);
  EXPECT_TRUE(filter.ok());
  if (!filter.ok()) return 1e9;
  double sum = 0.0;
  int count = 0;
  for (size_t i = 0; i < c.samples.size(); ++i) {
    const ImuSample& s = c.samples[i];
    EXPECT_TRUE((*filter)->Update(s).ok());
    const AttitudeEstimate estimate = (*filter)->estimate();
    testing::DumpEstimate(estimate);
    const double e = AttitudeErrorOf(estimate.body_to_world, c.truth[i]).inclination_rad;
    if (s.t_s < from_s) continue;
    sum += e * e;
    ++count;
  }
  return std::sqrt(sum / std::max(count, 1)) / kDeg;
}

// Swaying at 0.5-1.5 Hz with 6-16 m/s^2 per sinusoid while tumbling (five seeds): the
// accelerometer's low-pass in the world frame must remove the linear acceleration. With one
// stage (accel_lowpass_order = 1, the filter before) 1.5 and 1.8 deg on two seeds and 1.10
// deg mean; with the default two stages 0.50-0.70, mean 0.62 (bounds 1.0 and 0.8). The 2-5 Hz
// shaking is removed by either (mean 0.54, what is left is the gyro's errors; the same bounds).
TEST(FastMotionTest, InclinationWhileSwayingAndTumbling) {
  const AttitudeFilterOptions options;  // the defaults, no magnetometer
  double sway_mean = 0.0, shake_mean = 0.0;
  for (int seed = 1; seed <= 5; ++seed) {
    const double sway = InclinationRmsDeg(MakeFastCase(seed, 60.0, 2.0, 0.5, 1.5), options, 10.0);
    const double shake = InclinationRmsDeg(MakeFastCase(seed, 60.0, 2.0, 2.0, 5.0), options, 10.0);
    EXPECT_LT(sway, 1.0) << "seed " << seed;
    EXPECT_LT(shake, 1.0) << "seed " << seed;
    sway_mean += sway / 5.0;
    shake_mean += shake / 5.0;
  }
  EXPECT_LT(sway_mean, 0.8);
  EXPECT_LT(shake_mean, 0.8);
}

TEST(FastMotionTest, LowpassOrderIsValidated) {
  AttitudeFilterOptions options;
  options.accel_lowpass_order = 3.0;
  const auto filter = CreateAttitudeFilter(options);
  ASSERT_FALSE(filter.ok());
  EXPECT_NE(filter.status().message().find("accel_lowpass_order"), std::string::npos);
  options.accel_lowpass_order = 1.0;
  EXPECT_TRUE(CreateAttitudeFilter(options).ok());
}


// Not a test: the simulated cases (five seeds each; both bands at half, once and twice the
// amplitudes) and the three BROAD trials with the options in ATT_OPT. Run with
//   build/tests/fast_motion_test --gtest_also_run_disabled_tests --gtest_filter='*Study'
TEST(FastMotionTest, DISABLED_Study) {
  const AttitudeFilterOptions options = testing::OptionsFromEnvironment();
  const double bands[2][2] = {{2.0, 5.0}, {0.5, 1.5}};
  for (const auto& band : bands) {
    for (const double scale : {0.5, 1.0, 2.0}) {
      double mean = 0.0;
      std::printf("simulated, %.1f-%.1f Hz x%.1f, 6D inclination RMS from 10 s (deg):", band[0], band[1], scale);
      for (int seed = 1; seed <= 5; ++seed) {
        const double e = InclinationRmsDeg(MakeFastCase(seed, 60.0, scale, band[0], band[1]), options, 10.0);
        mean += e / 5.0;
        std::printf(" %.3f", e);
      }
      std::printf("  mean %.3f\n", mean);
    }
  }
  double six_mean = 0.0, nine_mean = 0.0;
  for (const std::string& path : testing::BroadTrialPaths()) {
    const io::ImuRecording* trial = testing::BroadTrial(path);
    ASSERT_NE(trial, nullptr);
    AttitudeFilterOptions o = options;
    o.use_mag = false;
    const double six = testing::RunTrial(*trial, o).score.inclination_rmse_rad / kDeg;
    o.use_mag = true;
    const AttitudeScore nine = testing::RunTrial(*trial, o).score;
    six_mean += six / 3.0;
    nine_mean += nine.total_rmse_rad / kDeg / 3.0;
    std::printf("%s 6D inclination %.3f | 9D total %.3f inclination %.3f\n",
                path.substr(path.rfind('/') + 1, 2).c_str(), six, nine.total_rmse_rad / kDeg,
                nine.inclination_rmse_rad / kDeg);
  }
  std::printf("BROAD mean 6D inclination %.3f, 9D total %.3f\n", six_mean, nine_mean);
}

// Not a test: where the 6D inclination error of BROAD trial ATT_TRIAL (0, 1, 2: 02, 16, 25)
// comes from: its RMS binned by the raw accelerometer's ||a| - g| and by the gyro rate (over
// the last second), and a per-second series. Options from ATT_OPT. Run with
//   ATT_TRIAL=1 build/tests/fast_motion_test --gtest_also_run_disabled_tests --gtest_filter='*Trace'
TEST(FastMotionTest, DISABLED_Trace) {
  const int t = std::getenv("ATT_TRIAL") ? std::atoi(std::getenv("ATT_TRIAL")) : 1;
  const io::ImuRecording* trial = testing::BroadTrial(testing::BroadTrialPaths()[t]);
  ASSERT_NE(trial, nullptr);
  const AttitudeFilterOptions options = testing::OptionsFromEnvironment();
  auto filter = CreateAttitudeFilter(options);
  ASSERT_TRUE(filter.ok());
  constexpr int kBins = 6;
  const double acc_edges[kBins] = {0.25, 0.5, 1.0, 2.0, 4.0, 1e9};
  const double rate_edges[kBins] = {0.1, 0.3, 0.6, 1.0, 2.0, 1e9};
  double acc_sum[kBins] = {}, rate_sum[kBins] = {};
  int acc_n[kBins] = {}, rate_n[kBins] = {};
  double sec_sum = 0.0, sec_acc = 0.0, sec_rate = 0.0;
  int sec_n = 0, sec_all = 0;
  double next_print = 0.0;
  double acc_lp = 0.0, rate_lp = 0.0;
  for (size_t i = 0; i < trial->samples.size(); ++i) {
    const ImuSample& s = trial->samples[i];
    ASSERT_TRUE((*filter)->Update(s).ok());
    const double dep = std::abs(s.accel_mps2.norm() - 9.81);
    acc_lp += (dep - acc_lp) / 285.0;  // ~1 s mean
    rate_lp += (s.gyro_rps.norm() - rate_lp) / 285.0;
    if (!trial->movement[i] || !trial->truth[i].coeffs().allFinite()) continue;
    const double e = AttitudeErrorOf((*filter)->estimate().body_to_world, trial->truth[i]).inclination_rad / kDeg;
    int a = 0, r = 0;
    while (acc_lp > acc_edges[a]) ++a;
    while (rate_lp > rate_edges[r]) ++r;
    acc_sum[a] += e * e, ++acc_n[a];
    rate_sum[r] += e * e, ++rate_n[r];
    sec_sum += e * e, sec_acc += dep, sec_rate += s.gyro_rps.norm(), ++sec_n;
    ++sec_all;
    if (s.t_s >= next_print) {
      std::printf("t %6.1f  incl rms %.2f  mean ||a|-g| %.2f  mean rate %.2f\n", s.t_s, std::sqrt(sec_sum / sec_n),
                  sec_acc / sec_n, sec_rate / sec_n);
      sec_sum = sec_acc = sec_rate = 0.0, sec_n = 0;
      next_print = s.t_s + 5.0;
    }
  }
  for (int b = 0; b < kBins; ++b) {
    std::printf("||a|-g| (1 s mean) <= %-5g: %5.1f %% of samples, incl rms %.2f | rate (1 s mean) <= %-5g: %5.1f %%, incl rms %.2f\n",
                acc_edges[b], 100.0 * acc_n[b] / sec_all, std::sqrt(acc_sum[b] / std::max(acc_n[b], 1)), rate_edges[b],
                100.0 * rate_n[b] / sec_all, std::sqrt(rate_sum[b] / std::max(rate_n[b], 1)));
  }
}

}  // namespace
}  // namespace localizer::engine
