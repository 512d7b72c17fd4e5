#include "engine/sim/magnetic_disturbance.h"

#include <cmath>
#include <random>

namespace localizer::engine {
namespace {

// A direction uniform on the sphere: a normalised standard normal vector.
Eigen::Vector3d RandomDirection(std::mt19937_64& engine) {
  std::normal_distribution<double> normal(0.0, 1.0);
  Eigen::Vector3d v;
  do {
    v = Eigen::Vector3d(normal(engine), normal(engine), normal(engine));
  } while (v.norm() < 1e-6);
  return v.normalized();
}

}  // namespace

BodyFixedMagnet RandomBodyFixedMagnet(double offset_norm_uT, double soft_iron_fraction, double start_s, uint64_t seed) {
  std::mt19937_64 engine(seed);
  BodyFixedMagnet magnet;
  magnet.offset_uT = offset_norm_uT * RandomDirection(engine);
  std::uniform_real_distribution<double> uniform(-soft_iron_fraction, soft_iron_fraction);
  for (int i = 0; i < 3; ++i) {
    for (int j = i; j < 3; ++j) {
      const double e = uniform(engine);
      magnet.soft_iron(i, j) += e;
      if (i != j) magnet.soft_iron(j, i) += e;
    }
  }
  magnet.start_s = start_s;
  return magnet;
}

BodyFixedMagnet RandomSoftIronMagnet(double offset_norm_uT, double gain_fraction, double start_s, uint64_t seed) {
  std::mt19937_64 engine(seed);
  BodyFixedMagnet magnet;
  magnet.offset_uT = offset_norm_uT * RandomDirection(engine);
  // A rotation uniform over SO(3): a normalised standard normal quaternion.
  std::normal_distribution<double> normal(0.0, 1.0);
  Eigen::Quaterniond q;
  do {
    q.coeffs() << normal(engine), normal(engine), normal(engine), normal(engine);
  } while (q.coeffs().norm() < 1e-6);
  const Eigen::Matrix3d axes = q.normalized().toRotationMatrix();
  std::uniform_real_distribution<double> uniform(-gain_fraction, gain_fraction);
  Eigen::Vector3d gains;
  for (int i = 0; i < 3; ++i) gains(i) = 1.0 + uniform(engine);
  magnet.soft_iron = axes * gains.asDiagonal() * axes.transpose();
  magnet.start_s = start_s;
  return magnet;
}

PassingObject RandomPassingObject(double peak_norm_uT, double centre_s, double width_s, uint64_t seed) {
  std::mt19937_64 engine(seed);
  PassingObject object;
  object.peak_world_uT = peak_norm_uT * RandomDirection(engine);
  object.centre_s = centre_s;
  object.width_s = width_s;
  return object;
}

void AddBodyFixedMagnet(const BodyFixedMagnet& magnet, std::vector<ImuSample>* samples) {
  for (ImuSample& s : *samples) {
    if (s.t_s < magnet.start_s || !s.mag_uT.allFinite()) continue;
    s.mag_uT = magnet.soft_iron * s.mag_uT + magnet.offset_uT;
  }
}

void AddPassingObject(const PassingObject& object, const std::vector<Eigen::Quaterniond>& body_to_world,
                      std::vector<ImuSample>* samples) {
  const size_t n = std::min(samples->size(), body_to_world.size());
  for (size_t i = 0; i < n; ++i) {
    ImuSample& s = (*samples)[i];
    const double u = (s.t_s - object.centre_s) / object.width_s;
    if (std::abs(u) > 4.0 || !s.mag_uT.allFinite() || !body_to_world[i].coeffs().allFinite()) continue;
    s.mag_uT += body_to_world[i].normalized().conjugate() * (object.peak_world_uT * std::exp(-0.5 * u * u));
  }
}

}  // namespace localizer::engine
