// Positions for the sources a direction search found, where the array's wavefront curvature
// tells the range (issue 18): a volumetric array gives 3-D positions (a stated side, if any,
// only narrows the search); a planar array with the sources' side stated gives 3-D
// positions; a linear array gives 2-D positions in a stated plane that holds it, on the side
// stated within that plane.
//
// Model. A source at p reaches sensor m after |p - m| / c, so pair (i, j) (PairSpectra's
// order) peaks at lag_p(p) = (|p - m_i| - |p - m_j|) fs / c samples. The near-field
// spectrum S(p) = sum_p R_p(lag_p(p)), R_p the pair's GCC-PHAT from the frame's whole
// spectrum (PairSpectra::WholeAt: no source removed) or, for one source among several, from
// the spectrum with the others removed (Spectrum::kCurrent), is maximised near the direction
// u the far-field search gave (from the array's centroid c):
//   1. a coarse grid, from the frame's sampled GCC (linear interpolation between lags): at
//      32 ranges, geometric from min_range_m to max_range_m, along u and along every
//      direction of a window about it (linear arrays: cone angles within 30 degrees, 2
//      degrees apart; planar: a 11 x 11 grid of directions 3 degrees apart). The window is
//      needed because a far-field search misplaces a near source: its wavefront is curved, so
//      the plane wave that fits best is defocused, and in a room a wall's image further away
//      (in focus) can outscore it (measured: a line 1.7 apertures from a talker, RT60 0.4 s,
//      followed the image of the wall behind it, 16 degrees off);
//   2. from the best grid point on u and the best in the window (one start when they
//      coincide), Gauss-Newton on the position's free coordinates (3 in space, 2 in the
//      plane) with each pair's exact R_p, R_p' and R_p'', each step kept within half a
//      sample of lag on every pair, and on the stated side; the better end point is the fit.
// Far-field lags are the limit of lag_p(c + r u) as r grows, so a far source's S rises
// along the ray to max_range_m and the fit ends there.
//
// Range bound. Pair p's delay variance from its own peak: a GCC peak of height R and
// curvature R'' (per sample^2) with noise sigma_n per lag (PairSpectra::noise_sigma) moves
// by var = sigma_n^2 / (R (-R'')) samples^2 (small-error analysis of the peak; pairs with
// R <= 0 or R'' >= 0 at the fit are left out). The Fisher information of the free
// coordinates, sum_p grad lag_p grad lag_p^T / var_p, inverted, is the fit's covariance;
// its standard deviation along the line of sight from c is range_sd_m. The position is
// reported when range_sd_m <= kFarFieldRangeShare x range (engine/core/far_field.h, the
// rule a volumetric array's estimates use) and the fit lies inside the searched ranges;
// otherwise the frame gives the direction only (far field).
//
// Cost per source and frame: the grid's 32 x 31 (linear) or 32 x 121 (planar) points of P
// interpolated lookups, plus up to 2 x 8 Gauss-Newton steps of a few P exact evaluations (P
// pairs, each a pass over the B in-band bins; a probe's pair terms serve the next step and
// the bound). Measured (near_field_report; BENCHMARKS.md): 0.4-0.5 ms per frame and source
// for 8 microphones on a line at 16 kHz with 1024-sample frames, 1.0-1.3 ms on an
// 8-microphone circle.
#pragma once

#include <limits>
#include <vector>

#include "engine/core/measurement.h"
#include "engine/core/status.h"
#include "engine/core/types.h"
#include "engine/doa/array_shape.h"
#include "engine/doa/pair_spectra.h"

namespace localizer::engine {

struct NearFieldOptions {
  double sample_rate_hz = 16000.0;
  double sound_speed_mps = 343.0;
  // The sources' side: they lie where (p - centroid).source_side > 0. Required for planar
  // and linear arrays (zero: not stated; a volumetric array needs none). Planar arrays: not
  // in the array plane. Linear arrays: in source_plane, not along the axis.
  Vec3 source_side = Vec3::Zero();
  // Linear arrays: the plane that holds the array and the sources (a point on it and its
  // normal; the array's axis must lie in it, within 1e-3 rad, and its centroid within 1 %
  // of the aperture or 1 mm). Ignored for planar arrays.
  Vec3 plane_point_m = Vec3::Constant(std::numeric_limits<double>::quiet_NaN());
  Vec3 plane_normal = Vec3::Zero();
  // Ranges searched from the centroid (0: 0.1 and 50 apertures).
  double min_range_m = 0.0;
  double max_range_m = 0.0;
};

// One source's near-field fit.
struct NearFieldFix {
  static constexpr double kNan = std::numeric_limits<double>::quiet_NaN();
  bool near_field = false;                 // the range is bounded: position_m holds
  Vec3 position_m = Vec3::Constant(kNan);  // NaN when far field
  Mat3 covariance_m2 = Mat3::Constant(kNan);
  double range_m = kNan;     // of the fit from the centroid (also when far field)
  double range_sd_m = kNan;  // its standard deviation (above); NaN when it cannot be computed
  // Where the fit ended, also when far field (NaN when there was no fit): the lags there are
  // the ones that best describe the source's peaks in this frame (PairLag).
  Vec3 fitted_m = Vec3::Constant(kNan);
};

class NearFieldLocator {
 public:
  // INVALID_ARGUMENT naming what is missing or wrong: no source_side for a planar or linear
  // array, a linear array without source_plane, a plane that does
  // not hold the array, a side in a planar array's plane or along a linear array's axis.
  static StatusOr<NearFieldLocator> Create(const std::vector<Vec3>& sensors_m, const NearFieldOptions& options);

  const ArrayShapeInfo& shape() const { return shape_; }
  // Linear arrays: the unit direction in source_plane at cone angle theta from the axis, on
  // the stated side.
  Vec3 DirectionAt(double cone_angle_rad) const;

  // Which spectrum a fit reads.
  enum class Spectrum {
    kWhole,    // the frame's whole spectrum (PairSpectra::WholeValueAt): no source removed
    kCurrent,  // the spectra as they are now (PairSpectra::At): the caller removed the other
               // sources heard in the frame, so that their peaks do not add to this one's S
               // (two sources 1.8 apertures away: each fit summed the other's GCC, and its
               // range sd was optimistic by about 2x; ACCURACY.md)
  };

  // The source heard near unit direction `direction` (from the centroid) in `spectra`'s last
  // analysed frame, which must be of this array's sensors in the same order; `field` the
  // sampled GCC of the spectrum read (kWhole: SrpPhat::whole_field; kCurrent: what
  // PairSpectra::FillFields gives). No fit (all NaN) when the field does not match the
  // spectra or the direction is not finite.
  NearFieldFix Locate(const PairSpectra& spectra, const Measurement& field, const Vec3& direction,
                      Spectrum read = Spectrum::kWhole) const;
  // Pair p's lag (samples, PairSpectra's order and sign) for a source at position_m.
  double PairLag(const PairSpectra& spectra, int p, const Vec3& position_m) const;

 private:
  NearFieldLocator() = default;
  Vec3 PositionOf(const Eigen::Vector3d& x) const;  // free coordinates -> position
  Eigen::Vector3d CoordinatesOf(const Vec3& position_m) const;
  bool OnSide(const Vec3& position_m) const;  // true everywhere when no side is stated
  bool sided() const { return side_ != Vec3::Zero(); }
  // One pair at a probed position: d lag / d free coordinates, R_p and R_p''.
  struct PairTerm {
    Eigen::Vector3d lag_gradient = Eigen::Vector3d::Zero();
    double r = 0.0, d2r = 0.0;
  };
  // S at a position from the exact spectrum, its gradient and Gauss-Newton Hessian in the
  // free coordinates (one pass over every pair's bins), and the pair terms (for the step
  // limit and the range bound).
  struct Probe {
    Vec3 position_m = Vec3::Zero();
    double value = 0.0;
    Eigen::Vector3d gradient = Eigen::Vector3d::Zero();
    Eigen::Matrix3d hessian = Eigen::Matrix3d::Zero();
    std::vector<PairTerm> pairs;
  };
  Probe ProbeAt(const PairSpectra& spectra, const Vec3& position_m, Spectrum read) const;
  double CoarseSpectrum(const PairSpectra& spectra, const Measurement& field, const Vec3& position_m) const;
  std::vector<Vec3> CandidateDirections(const Vec3& u) const;              // u first, then its window
  double Lag(int i, int j, const Vec3& position_m, Vec3* gradient) const;  // samples; d lag / d position
  NearFieldFix Bound(const PairSpectra& spectra, const Probe& fit) const;
  // In the plane (2 free coordinates): the normal's row and column of a 3 x 3 matrix over
  // the free coordinates set to `diagonal` on the diagonal and 0 elsewhere.
  void Pin(Eigen::Matrix3d* m, double diagonal) const;

  ArrayShapeInfo shape_;
  NearFieldOptions options_;
  std::vector<Vec3> sensors_m_;
  int free_ = 3;                                         // free coordinates: 3, or 2 in the plane
  Eigen::Matrix3d basis_ = Eigen::Matrix3d::Identity();  // columns: the free axes (p = c + B x)
  Vec3 side_ = Vec3::Zero();  // unit; linear: in the plane, across the axis; zero: none (volumetric)
  double min_range_m_ = 0.0, max_range_m_ = 0.0;
};

}  // namespace localizer::engine
