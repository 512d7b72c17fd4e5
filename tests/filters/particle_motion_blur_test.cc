// Motion blur in the particle filter's likelihood (ParticleFilterOptions::motion_blur): a
// particle whose velocity moves a pair's delay at rate r within the frame takes that pair's
// Student-t with variance sigma^2 + K r^2 V (V = Measurement::window_time_var_s2, K = the
// option x min(1, 2 / peak_snr): particle_math.h), so a still particle's likelihood is what it
// was and a moving one's is wider by its own rate, the more so the weaker the peak.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "engine/filters/particle_set.h"
#include "tests/filters/tdoa_frames.h"

namespace localizer::engine {
namespace {

constexpr double kSigmaS = 5e-6;
constexpr double kDof = 4.0;
constexpr double kWindowVarS2 = 0.02 * 0.34 * 0.34;  // a Hann frame of 0.34 s (16384 at 48 kHz)

// The log-weight change of one particle at (position, velocity) from one Weigh of `m`.
double WeighOne(const ArrayGeometry& array, double blur, const Vec3& position_m, const Vec3& velocity_mps,
                const Measurement& m) {
  ParticleFilterOptions o;
  o.particles = 16;
  o.seed = 3;
  o.motion_blur = blur;
  o.SetSingleMotion();
  ParticleSet set(array, o);
  Vec6 mean;
  mean << position_m, velocity_mps;
  set.SampleGaussian(mean, Mat6::Zero());
  const double before = set.log_weights()[0];
  std::vector<InnovationMoments> innovations;
  set.Weigh(m, std::vector<int>(m.pairs.size(), 1), Likelihood::kPeak, std::vector<double>(m.pairs.size(), kSigmaS),
            kDof, 1.0, &innovations);
  return set.log_weights()[0] - before;
}

// The same, written out in double: pair p's predicted delay at the instant it describes,
// h = tau(x) - (d / 2) r, and its Student-t with variance sigma^2 + K r^2 V (up to the
// constants every particle shares).
double Expected(const ArrayGeometry& array, double blur, const Vec3& position_m, const Vec3& velocity_mps,
                const Measurement& m) {
  const double share = blur * std::min(1.0, 2.0 / m.pairs.front().peak_snr);
  const Eigen::VectorXd tau = array.Tdoa(position_m);
  const Eigen::VectorXd rate = array.TdoaJacobian(position_m) * velocity_mps;
  double ll = 0.0;
  for (size_t p = 0; p < m.pairs.size(); ++p) {
    const auto i = static_cast<Eigen::Index>(p);
    const double d = m.pairs[p].delay_s;
    const double e = (d - (tau(i) - 0.5 * d * rate(i))) / kSigmaS;
    const double widen = 1.0 + share * m.window_time_var_s2 * rate(i) * rate(i) / (kSigmaS * kSigmaS);
    ll += -0.5 * (kDof + 1.0) * std::log(1.0 + e * e / (kDof * widen)) - 0.5 * std::log(widen);
  }
  return ll;
}

// Delays `off` sigmas from a source 1.5 m from a 0.45 m tetrahedron in air (alternating in
// sign), peaks peak_snr noise sds high.
Measurement FrameNear(const ArrayGeometry& array, const Vec3& source_m, double peak_snr, double off = 3.0) {
  Measurement m;
  m.t_s = 1.0;
  m.sample_rate_hz = 48000.0;
  m.window_time_var_s2 = kWindowVarS2;
  const Eigen::VectorXd tau = array.Tdoa(source_m);
  for (int p = 0; p < array.pair_count(); ++p) {
    PairMeasurement pm;
    pm.sensor = array.sensor_of_pair(p);
    pm.delay_s = tau(p) + (p % 2 == 0 ? off : -off) * kSigmaS;
    pm.delay_sigma_s = kSigmaS;
    pm.peak_snr = peak_snr;
    pm.quality = 10.0;
    m.pairs.push_back(pm);
  }
  return m;
}

TEST(ParticleMotionBlur, AMovingParticlesPairsWidenByItsOwnDelayRates) {
  const ArrayGeometry array = Tetrahedron(0.45, Vec3::Zero(), 343.0);
  const Vec3 source_m(1.2, 0.6, 0.6);
  const Vec3 still = Vec3::Zero();
  const Vec3 crossing(-1.0, 2.5, 0.0);  // 2.7 m/s, mostly across the line of sight
  const Eigen::VectorXd rate = array.TdoaJacobian(source_m) * crossing;
  // The crossing particle's delays move by up to |r| sqrt(V) = this many sigmas in the frame.
  const double blur_sigmas = rate.cwiseAbs().maxCoeff() * std::sqrt(kWindowVarS2) / kSigmaS;
  ASSERT_GT(blur_sigmas, 3.0) << "the case must blur";
  for (const double peak_snr : {1.5, 8.0, 40.0}) {
    const Measurement m = FrameNear(array, source_m, peak_snr);
    for (const double blur : {0.0, 0.25, 1.0}) {
      for (const Vec3& v : {still, crossing}) {
        const double got = WeighOne(array, blur, source_m, v, m);
        const double want = Expected(array, blur, source_m, v, m);
        EXPECT_NEAR(got, want, 2e-3 * std::abs(want) + 1e-3)
            << "peak snr " << peak_snr << ", blur " << blur << ", speed " << v.norm();
      }
    }
    // A still particle does not see the blur.
    EXPECT_NEAR(WeighOne(array, 1.0, source_m, still, m), WeighOne(array, 0.0, source_m, still, m), 1e-6);
  }
  // The moving particle is judged less sharply, the more so the weaker the peak: what 3-sigma
  // innovations cost it against none.
  const auto cost = [&](double blur, double peak_snr) {
    return WeighOne(array, blur, source_m, crossing, FrameNear(array, source_m, peak_snr, 0.0)) -
           WeighOne(array, blur, source_m, crossing, FrameNear(array, source_m, peak_snr, 3.0));
  };
  EXPECT_GT(cost(0.0, 40.0), 6.0);  // three pairs at 3 sigmas: 2.9 nats each
  EXPECT_LT(cost(1.0, 40.0), 0.5 * cost(0.0, 40.0));
  EXPECT_LT(cost(1.0, 8.0), 0.5 * cost(1.0, 40.0));
}

TEST(ParticleMotionBlur, AFrontEndThatStatesNoWindowLeavesTheLikelihoodAsItWas) {
  const ArrayGeometry array = Tetrahedron(0.45, Vec3::Zero(), 343.0);
  const Vec3 source_m(1.2, 0.6, 0.6);
  Measurement m = FrameNear(array, source_m, 8.0);
  m.window_time_var_s2 = 0.0;
  const Vec3 crossing(-1.0, 2.5, 0.0);
  EXPECT_EQ(WeighOne(array, 1.0, source_m, crossing, m), WeighOne(array, 0.0, source_m, crossing, m));
}

TEST(ParticleMotionBlur, TheShareIsValidatedNamingTheField) {
  ParticleFilterOptions o;
  o.motion_blur = 1.5;
  const Status s = o.Validate();
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.message().find("motion_blur"), std::string::npos) << s.message();
}

}  // namespace
}  // namespace localizer::engine
