// Online hard-iron estimation: the body-fixed offset a magnet or magnetised part riding on
// the sensor adds to the magnetometer, learnt from the rotating field while the filter runs.
//
// Model. The reading is m_k = R_k^T m_w + b (+ noise): the world's field m_w turned into the
// body by the attitude R_k (body -> world), plus the offset b fixed in the body. Rotated
// into the world with the filter's attitude, y_k = R_k m_k = m_w + R_k b: linear in the six
// unknowns (m_w, b). They are the exponentially weighted least-squares solution over the
// recent past (time constant forget_s), from running sums (each sample adds to
// S0 = sum w, SR = sum w R_k, Sy = sum w y_k, Sm = sum w m_k, Smm = sum w |m_k|^2):
//     M = SR / S0  (the mean attitude matrix),   A = I - M^T M,
//     A b = Sm / S0 - M^T Sy / S0,               m_w = Sy / S0 - M b,
//     residual^2 = (Smm - m_w . Sy - b . Sm) / S0   (mean squared misfit per sample).
// A (symmetric, 0 <= A <= I) is the information the rotations give about b per sample: 0
// when the sensor has not turned (the offset and the world field are then the same
// thing), I when its attitudes are spread over the sphere. Using the gyro-tracked attitude
// instead of a sphere fit to |m_k| keeps the fit linear and lets partial rotations count.
// The filter's heading may drift slowly within the window; that only turns m_w about Up.
//
// Confidence. The offset's component along the world's horizontal axis across the field
// turns the heading by about that component / the field's horizontal part (0.3 µT is already
// 1 degree in Berlin's 17 µT horizontal field), and as the sensor turns, any body axis can
// become that one. So the fit is trusted when the smallest eigenvalue of A (the diversity
// along the worst-observed body axis) is at least min_diversity and the RMS residual is at
// most
// max_residual (a fraction of |m_w|): the field was then a constant world field plus a
// constant body offset over the window. A world-frame disturbance (an iron object passed
// by), a magnet that appears mid-window or soft iron beyond the tolerance leave a large
// residual, and the fit is not trusted until the window has forgotten them.
//
// Sums. Add() keeps a superset of what the hard-iron fit needs (MagCalibrationSums: the
// second moments of m_k and the products m_k,i R_k), so the soft-iron fit
// (soft_iron_estimator.h) reads the same window without sums of its own.
//
// Cost: about 60 multiply-adds per Add() (the 27 products m_k,i R_k are most of it);
// Solve() (a 3x3 inverse and a 3x3 symmetric eigenvalue problem in closed form) is meant to
// run a few times per second.
#pragma once

#include <Eigen/Core>

namespace localizer::engine {

// Exponentially weighted sums over the readings m_k and attitudes R_k (body -> world) of the
// window, each sample with weight 1 when added and older ones down-weighted (see Add()).
struct MagCalibrationSums {
  double s0 = 0.0;                                // sum w
  Eigen::Matrix3d sr = Eigen::Matrix3d::Zero();   // sum w R_k
  Eigen::Vector3d sm = Eigen::Vector3d::Zero();   // sum w m_k (µT)
  Eigen::Matrix3d smm = Eigen::Matrix3d::Zero();  // sum w m_k m_k^T (µT^2)
  Eigen::Matrix3d smr[3] = {Eigen::Matrix3d::Zero(), Eigen::Matrix3d::Zero(),
                            Eigen::Matrix3d::Zero()};  // [i]: sum w m_k,i R_k (µT)

  // sum w R_k m_k = sum_i smr[i].col(i): the readings rotated into the world.
  Eigen::Vector3d Sy() const { return smr[0].col(0) + smr[1].col(1) + smr[2].col(2); }
};

struct HardIronFit {
  Eigen::Vector3d offset_uT = Eigen::Vector3d::Zero();       // b, body frame
  Eigen::Vector3d field_world_uT = Eigen::Vector3d::Zero();  // m_w, world frame (the filter's)
  double diversity = 0.0;                                    // smallest eigenvalue of A, [0, 1]
  // 1 / (u^T A^-1 u), u the heading-relevant axis at the current attitude (diagnostics: it
  // can be large at one attitude and small at the next).
  double heading_diversity = 0.0;
  double residual_uT = 0.0;  // RMS misfit per sample
  bool trusted = false;
};

class HardIronEstimator {
 public:
  HardIronEstimator(double forget_s, double min_diversity, double max_residual)
      : forget_s_(forget_s), min_diversity_(min_diversity), max_residual_(max_residual) {}

  // Adds one reading `mag_uT` taken at attitude `body_to_world` (its rotation matrix), dt_s
  // after the previous one (older samples are down-weighted by 1 - dt_s / forget_s).
  void Add(const Eigen::Matrix3d& body_to_world, const Eigen::Vector3d& mag_uT, double dt_s) {
    const double keep = forget_s_ > dt_s ? 1.0 - dt_s / forget_s_ : 0.0;
    sums_.s0 = keep * sums_.s0 + 1.0;
    sums_.sr = keep * sums_.sr + body_to_world;
    sums_.sm = keep * sums_.sm + mag_uT;
    sums_.smm = keep * sums_.smm + mag_uT * mag_uT.transpose();
    for (int i = 0; i < 3; ++i) sums_.smr[i] = keep * sums_.smr[i] + mag_uT(i) * body_to_world;
  }

  // Forgets every sample (after a change of the offset or the field, so the fit restarts).
  void Reset() { sums_ = MagCalibrationSums{}; }

  // The fit over the samples added so far (not trusted with fewer than a few), judged for the
  // current attitude `body_to_world`.
  HardIronFit Solve(const Eigen::Matrix3d& body_to_world) const;

  // The RMS misfit over the same window of another offset (with the world field that suits
  // it best): (Smm - 2 b . Sm + |b|^2 S0) / S0 - |Sy / S0 - M b|^2, square-rooted.
  double ResidualWith(const Eigen::Vector3d& offset_uT) const;
  // That best world field: (Sy - SR b) / S0.
  Eigen::Vector3d FieldWith(const Eigen::Vector3d& offset_uT) const {
    return sums_.s0 > 0.0 ? Eigen::Vector3d((sums_.Sy() - sums_.sr * offset_uT) / sums_.s0) : Eigen::Vector3d::Zero();
  }
  // The misfit a trusted fit may have: max_residual |m_w| + 0.01 |b|.
  double AllowedResidual(const HardIronFit& fit) const;

  double weight() const { return sums_.s0; }
  const MagCalibrationSums& sums() const { return sums_; }
  double max_residual() const { return max_residual_; }

 private:
  double forget_s_;
  double min_diversity_;
  double max_residual_;
  MagCalibrationSums sums_;
};

}  // namespace localizer::engine
