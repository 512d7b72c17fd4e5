// A point in R^D with Gaussian uncertainty: a mean and its covariance (symmetric positive
// definite; the roles check finiteness at the tracker's edge, not definiteness).
//
// The currency of the track-while-scan roles. As a measurement it is the value z and its
// noise covariance R (a radar plot converted to Cartesian, or any other position fix); as a
// prediction it is what a track expects to be measured, H x and H P H^T (cv_kalman.h: the
// predicted position and its covariance). Nothing here knows where the numbers came from.
#pragma once

#include <Eigen/Core>

namespace localizer::engine::tws {

template <int D>
struct Gaussian {
  Eigen::Matrix<double, D, 1> mean;
  Eigen::Matrix<double, D, D> covariance;
};

}  // namespace localizer::engine::tws
