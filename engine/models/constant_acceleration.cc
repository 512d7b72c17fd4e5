#include "engine/models/constant_acceleration.h"

namespace localizer::engine {

Eigen::MatrixXd KronAxes(const Eigen::Matrix3d& axis) {
  Eigen::MatrixXd m = Eigen::MatrixXd::Zero(9, 9);
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) m.block<3, 3>(3 * i, 3 * j) = axis(i, j) * Eigen::Matrix3d::Identity();
  }
  return m;
}

namespace {
Eigen::Matrix3d AxisTransition(double t) {
  Eigen::Matrix3d f;
  f << 1.0, t, 0.5 * t * t, 0.0, 1.0, t, 0.0, 0.0, 1.0;
  return f;
}
}  // namespace

Eigen::VectorXd ConstantAccelerationModel::Propagate(const Eigen::VectorXd& x, double dt_s) const {
  return KronAxes(AxisTransition(dt_s)) * x;
}

Eigen::MatrixXd ConstantAccelerationModel::Jacobian(const Eigen::VectorXd&, double dt_s) const {
  return KronAxes(AxisTransition(dt_s));
}

Eigen::MatrixXd ConstantAccelerationModel::ProcessNoise(const Eigen::VectorXd&, double dt_s) const {
  const double t = dt_s, t2 = t * t, t3 = t2 * t;
  Eigen::Matrix3d q;
  q << t3 * t2 / 20.0, t2 * t2 / 8.0, t3 / 6.0,  //
      t2 * t2 / 8.0, t3 / 3.0, t2 / 2.0,         //
      t3 / 6.0, t2 / 2.0, t;
  return KronAxes(q_ * q);
}

}  // namespace localizer::engine
