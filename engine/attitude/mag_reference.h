// The magnetic field's reference norm and dip, learnt at start, and the test that flags a
// disturbed sample against them (shared by both attitude filters).
//
// Over the first `reference_s` seconds of samples offered, Observe() accumulates the field's
// norm |m| (µT) and dip angle
//     dip = atan2(-m_up, sqrt(m_east^2 + m_north^2))      (positive: field points down)
// computed from the world-frame field m = R_est m_body, so the dip depends on the estimated
// tilt; the references are their means. Afterwards a sample is undisturbed when
//     | |m| - norm_ref | <= norm_tolerance * norm_ref  and  |dip - dip_ref| <= dip_tolerance_rad.
// During learning every sample counts as undisturbed (there is nothing to compare with yet):
// a field disturbed from the very start is learnt as the reference.
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <cmath>

namespace localizer::engine {

class MagReference {
 public:
  MagReference(double reference_s, double norm_tolerance, double dip_tolerance_rad)
      : reference_s_(reference_s),
        norm_tolerance_(norm_tolerance),
        cos_tolerance_(std::cos(std::min(dip_tolerance_rad, M_PI))) {}

  // Learns from or tests one world-frame field sample; true when it may be used.
  bool Observe(const Eigen::Vector3d& field_world_uT, double t_s) {
    const double horizontal = field_world_uT.head<2>().norm();
    const double norm = field_world_uT.norm();
    if (count_ == 0) start_t_s_ = t_s;
    if (!learnt_ && t_s - start_t_s_ <= reference_s_) {
      ++count_;
      norm_sum_ += norm;
      dip_sum_ += std::atan2(-field_world_uT.z(), horizontal);
      return true;
    }
    if (!learnt_) {
      learnt_ = true;
      cos_dip_ref_ = std::cos(dip_ref_rad());
      sin_dip_ref_ = std::sin(dip_ref_rad());
    }
    if (std::abs(norm - norm_ref_uT()) > norm_tolerance_ * norm_ref_uT() || norm <= 0.0) {
      return false;
    }
    // |dip - dip_ref| <= tolerance as cos(dip - dip_ref) >= cos(tolerance) (both dips lie in
    // [-pi/2, pi/2], so their difference within [-pi, pi]): no arc tangent per sample.
    const double cos_difference = (horizontal * cos_dip_ref_ - field_world_uT.z() * sin_dip_ref_) / norm;
    return cos_difference >= cos_tolerance_;
  }

  // Replaces the reference (ends learning): the field of a trusted hard-iron fit
  // (hard_iron_estimator.h), whose norm and dip describe the field with the offset removed.
  void Set(double norm_uT, double dip_rad) {
    learnt_ = true;
    count_ = 1;
    norm_sum_ = norm_uT;
    dip_sum_ = dip_rad;
    cos_dip_ref_ = std::cos(dip_rad);
    sin_dip_ref_ = std::sin(dip_rad);
  }

  bool learnt() const { return learnt_; }
  double norm_ref_uT() const { return count_ > 0 ? norm_sum_ / static_cast<double>(count_) : 0.0; }
  double dip_ref_rad() const { return count_ > 0 ? dip_sum_ / static_cast<double>(count_) : 0.0; }

 private:
  double reference_s_;
  double norm_tolerance_;
  double cos_tolerance_;
  double cos_dip_ref_ = 1.0;
  double sin_dip_ref_ = 0.0;
  double start_t_s_ = 0.0;
  long count_ = 0;
  double norm_sum_ = 0.0;
  double dip_sum_ = 0.0;
  bool learnt_ = false;
};

}  // namespace localizer::engine
