#include "engine/sim/platform_motion.h"

#include <cmath>
#include <random>

namespace localizer::engine {
namespace {

// Rz(yaw) Ry(pitch) Rx(roll): the same convention as engine/attitude (sim does not depend
// on that stage, so it is written here again).
Eigen::Quaterniond QuaternionOfEuler(const Eigen::Vector3d& e) {
  return Eigen::Quaterniond(Eigen::AngleAxisd(e.z(), Eigen::Vector3d::UnitZ()) *
                            Eigen::AngleAxisd(e.y(), Eigen::Vector3d::UnitY()) *
                            Eigen::AngleAxisd(e.x(), Eigen::Vector3d::UnitX()));
}

Eigen::Quaterniond Spin(const Eigen::Vector3d& rate_rps, double t_s) {
  const Eigen::Vector3d angle = rate_rps * t_s;
  const double norm = angle.norm();
  if (norm == 0.0) return Eigen::Quaterniond::Identity();
  return Eigen::Quaterniond(Eigen::AngleAxisd(norm, angle / norm));
}

}  // namespace

AttitudeTrajectory AttitudeTrajectory::ConstantRate(const Eigen::Vector3d& start_euler_rad,
                                                    const Eigen::Vector3d& body_rate_rps) {
  AttitudeTrajectoryOptions options;
  options.euler0_rad = start_euler_rad;
  options.constant_rate_rps = body_rate_rps;
  return AttitudeTrajectory(options);
}

Eigen::Quaterniond AttitudeTrajectory::At(double t_s) const {
  const AttitudeTrajectoryOptions& o = options_;
  const Eigen::Vector3d phase = 2.0 * M_PI * o.frequency_hz * t_s + o.phase_rad;
  const Eigen::Vector3d euler =
      o.euler0_rad + o.euler_rate_rps * t_s + o.amplitude_rad.cwiseProduct(phase.array().sin().matrix());
  return (QuaternionOfEuler(euler) * Spin(o.constant_rate_rps, t_s)).normalized();
}

Eigen::Vector3d AttitudeTrajectory::BodyRate(double t_s) const {
  const AttitudeTrajectoryOptions& o = options_;
  const Eigen::Vector3d phase = 2.0 * M_PI * o.frequency_hz * t_s + o.phase_rad;
  const Eigen::Vector3d e =
      o.euler0_rad + o.euler_rate_rps * t_s + o.amplitude_rad.cwiseProduct(phase.array().sin().matrix());
  const Eigen::Vector3d de =
      o.euler_rate_rps +
      (2.0 * M_PI * o.frequency_hz).cwiseProduct(o.amplitude_rad).cwiseProduct(phase.array().cos().matrix());
  const double sr = std::sin(e.x()), cr = std::cos(e.x());
  const double sp = std::sin(e.y()), cp = std::cos(e.y());
  const Eigen::Vector3d w_e(de.x() - de.z() * sp, de.y() * cr + de.z() * sr * cp, -de.y() * sr + de.z() * cr * cp);
  return Spin(o.constant_rate_rps, t_s).conjugate() * w_e + o.constant_rate_rps;
}

Eigen::Vector3d AttitudeTrajectory::LinearAccelerationWorld(double t_s) const {
  return options_.linear_amplitude_mps2 * std::sin(2.0 * M_PI * options_.linear_frequency_hz * t_s);
}

std::vector<ImuSample> SynthesiseImu(const AttitudeTrajectory& trajectory, double rate_hz, double duration_s,
                                     const ImuNoise& noise, uint64_t seed) {
  std::vector<ImuSample> samples;
  if (!(rate_hz > 0.0) || !(duration_s > 0.0)) return samples;
  // Its own stream constant ("IMU"), so an IMU seeded like a scenario draws other numbers.
  std::seed_seq sequence{static_cast<uint32_t>(seed), static_cast<uint32_t>(seed >> 32), 0x494d55u};
  std::mt19937_64 engine(sequence);
  std::normal_distribution<double> normal(0.0, 1.0);
  auto draw = [&](double sd) { return Eigen::Vector3d(sd * normal(engine), sd * normal(engine), sd * normal(engine)); };
  const auto count = static_cast<int64_t>(std::floor(duration_s * rate_hz)) + 1;
  samples.reserve(static_cast<size_t>(count));
  for (int64_t k = 0; k < count; ++k) {
    const double t_s = static_cast<double>(k) / rate_hz;
    const Eigen::Quaterniond to_body = trajectory.At(t_s).conjugate();
    ImuSample s;
    s.t_s = t_s;
    s.gyro_rps = trajectory.BodyRate(t_s) + noise.gyro_bias_rps + draw(noise.gyro_noise_sd_rps);
    s.accel_mps2 = to_body * (trajectory.LinearAccelerationWorld(t_s) + Eigen::Vector3d(0.0, 0.0, noise.gravity_mps2)) +
                   draw(noise.accel_noise_sd_mps2);
    const Eigen::Vector3d mag_noise = draw(noise.mag_noise_sd_uT);
    if (noise.with_mag) {
      Eigen::Vector3d field = noise.mag_world_uT;
      if (t_s >= noise.disturbance_start_s && t_s < noise.disturbance_end_s) {
        field += noise.mag_disturbance_world_uT;
      }
      s.mag_uT = to_body * field + mag_noise;
    }
    samples.push_back(s);
  }
  return samples;
}

}  // namespace localizer::engine
