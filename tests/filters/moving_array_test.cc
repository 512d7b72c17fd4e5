// A tracker on a moving platform: the array turns under a static source. Told each frame
// where its sensors are now (Tracker::SetArray), every CPU filter holds the source; left
// with the first pose it is dragged off. SetArray refuses anything but a rigid motion.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <cstdio>
#include <memory>
#include <random>
#include <string>

#include "engine/filters/imm_filter.h"
#include "engine/filters/kalman_filter.h"
#include "engine/filters/multi_model_pf.h"
#include "engine/filters/particle_filter.h"
#include "tests/filters/manoeuvre_track.h"

namespace localizer::engine {
namespace {

ArrayGeometry BodyArray() {
  // A tetrahedron with 1.5 m edges around the platform origin.
  const double a = 1.5 / std::sqrt(8.0);
  return *ArrayGeometry::Create({Vec3(a, a, a), Vec3(a, -a, -a), Vec3(-a, a, -a), Vec3(-a, -a, a)}, 1500.0);
}

// Yaw at 0.5 rad/s and a slow roll: a buoy swinging on its mooring.
Mat3 Attitude(double t_s) {
  return (Eigen::AngleAxisd(0.5 * t_s, Vec3::UnitZ()) * Eigen::AngleAxisd(0.2 * std::sin(t_s), Vec3::UnitX()))
      .toRotationMatrix();
}

std::unique_ptr<Tracker> Make(const std::string& kind, const ArrayGeometry& array) {
  KalmanOptions kalman;
  kalman.tdoa_sigma_s = 2e-6;
  kalman.motion.accel_noise_mps2 = 0.05;
  ParticleFilterOptions particle;
  particle.particles = 2048;
  particle.tdoa_sigma_s = 2e-6;
  particle.accel_noise_mps2 = 0.05;
  particle.seed = 3;
  if (kind == "ekf") return std::move(KalmanFilter::Create(array, kalman)).value();
  if (kind == "pf") return std::move(ParticleFilter::Create(array, particle)).value();
  if (kind == "imm") {
    ImmOptions imm;
    imm.kalman = kalman;
    for (ImmMode& m : imm.modes) m.motion = kalman.motion;
    return std::move(ImmFilter::Create(array, imm)).value();
  }
  MultiModelPfOptions mmpf;
  mmpf.particle = particle;
  return std::move(MultiModelParticleFilter::Create(array, mmpf)).value();
}

struct Outcome {
  double error_m = 0.0;  // final position error
  int gated = 0;         // frames the Kalman gate refused (of 160)
};

// After 8 s at 20 frames/s, the source still at (6, 4, -2) m.
Outcome Track(const std::string& kind, bool follow) {
  const ArrayGeometry body = BodyArray();
  const Vec3 source(6.0, 4.0, -2.0);
  auto tracker = Make(kind, body);
  TrackState start;
  start.mean.head<3>() = source + Vec3(0.1, -0.1, 0.1);
  start.covariance.topLeftCorner<3, 3>() = 0.04 * Mat3::Identity();
  start.covariance.bottomRightCorner<3, 3>() = 0.01 * Mat3::Identity();
  EXPECT_TRUE(tracker->Initialise(start).ok());
  std::mt19937_64 rng(11);
  std::normal_distribution<double> noise(0.0, 2e-6);
  const double dt = 0.05;
  Outcome out;
  for (int k = 1; k <= 160; ++k) {
    const double t = k * dt;
    const ArrayGeometry now = body.Moved(Attitude(t), Vec3::Zero());
    if (follow) {
      EXPECT_TRUE(tracker->SetArray(now).ok());
    }
    tracker->Predict(dt);
    auto report = tracker->Update(testing::TdoaFrame(now, source, Vec3::Zero(), t, noise, rng));
    EXPECT_TRUE(report.ok());
    if (report.ok() && report->gated) ++out.gated;
  }
  out.error_m = (tracker->State().mean.head<3>() - source).norm();
  return out;
}

class MovingArray : public ::testing::TestWithParam<std::string> {};

TEST_P(MovingArray, FollowingThePoseHoldsTheSourceIgnoringItDoesNot) {
  const Outcome followed = Track(GetParam(), true);
  const Outcome fixed = Track(GetParam(), false);
  std::printf("%s: following the pose %.3f m (%d frames gated), first pose kept %.3f m (%d gated)\n",
              GetParam().c_str(), followed.error_m, followed.gated, fixed.error_m, fixed.gated);
  EXPECT_LT(followed.error_m, 0.3) << GetParam();
  EXPECT_LE(followed.gated, 8) << GetParam();
  // The array turns by 4 rad: with its first pose the model is wrong by metres of position,
  // so the particle filters are dragged off (measured: 20-60 x the error of following the
  // pose; how far depends on the filter's random stream, so the bound is relative) and the
  // Kalman gate refuses most frames (the filter coasts blind on its prior).
  EXPECT_TRUE(fixed.error_m > 10.0 * followed.error_m || fixed.gated > 80)
      << GetParam() << ": " << fixed.error_m << " m, " << fixed.gated << " gated";
}

INSTANTIATE_TEST_SUITE_P(CpuTrackers, MovingArray, ::testing::Values("ekf", "pf", "imm", "mmpf"));

TEST(MovingArray, SetArrayRefusesAnythingButARigidMotion) {
  const ArrayGeometry body = BodyArray();
  auto tracker = Make("ekf", body);
  EXPECT_TRUE(tracker->SetArray(body.Moved(Attitude(1.0), Vec3(3.0, -2.0, 1.0))).ok());
  std::vector<Vec3> stretched = body.sensors_m();
  stretched[2] *= 1.1;
  const Status bent = tracker->SetArray(*ArrayGeometry::Create(stretched, 1500.0));
  EXPECT_EQ(bent.code(), StatusCode::kInvalidArgument);
  EXPECT_NE(bent.message().find("rigid"), std::string::npos) << bent.message();
  const Status other_c = tracker->SetArray(*ArrayGeometry::Create(body.sensors_m(), 343.0));
  EXPECT_EQ(other_c.code(), StatusCode::kInvalidArgument);
  const Status other_ref = tracker->SetArray(*ArrayGeometry::Create(body.sensors_m(), 1500.0, 1));
  EXPECT_EQ(other_ref.code(), StatusCode::kInvalidArgument);
}

TEST(MovingArray, MovedKeepsDistancesAndDelayBounds) {
  const ArrayGeometry body = BodyArray();
  const ArrayGeometry moved = body.Moved(Attitude(2.0), Vec3(10.0, 0.0, -5.0));
  for (int p = 0; p < body.pair_count(); ++p) EXPECT_DOUBLE_EQ(moved.max_delay_s(p), body.max_delay_s(p));
  EXPECT_NEAR(moved.centroid_m().x(), 10.0, 1e-12);
  EXPECT_NEAR(moved.aperture_m(), body.aperture_m(), 1e-12);
  // The TDOA of a source seen from the moved array equals the body array's TDOA of that
  // source expressed in the body frame.
  const Vec3 source(3.0, -4.0, 2.0);
  const Vec3 in_body = Attitude(2.0).transpose() * (source - Vec3(10.0, 0.0, -5.0));
  EXPECT_LT((moved.Tdoa(source) - body.Tdoa(in_body)).norm(), 1e-15);
}

}  // namespace
}  // namespace localizer::engine
