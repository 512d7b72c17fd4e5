// Acquisition: every position the frame's TDOAs allow, before (and whenever) the tracker
// has no trustworthy state; and the presence test, globally or around a track.
//
// Search. The plausible volume (a sphere of search_radius_m about the array centroid,
// intersected with the bounds box) is cut into cells: azimuth_cells x polar_cells equal-area
// directions (uniform in azimuth and in cos(polar angle)) times range_cells shells, log-spaced
// from 0.05 apertures (the innermost holds the centre) to the radius. Each cell gets an
// upper bound of the normalised spatial spectrum (lag_field.h) inside it:
//     U(cell) = sum_p max{ n_p(l) : |l - lag_p(centre)| <= |grad lag_p| r_cell + 0.5 }
// with lag_p(x) = h_p(x) fs and r_cell the cell's circumradius (a cell's lags cannot stray
// further). Cells are refined in decreasing U until refinement_budget cells are used or U
// falls below the best mode found minus mode_margin sqrt(P) (branch and bound: such a cell
// cannot hold a mode close to the best). A refinement picks, per pair, the largest peak
// within the cell's lags, solves the weighted TDOA least squares from the cell centre
// (Gauss–Newton, weights 1/sigma_p^2, sigma_p from the peak's curvature and height:
// sigma_p ~ 1 / (n_peak sqrt(-g''/g)) samples, the delay's CRLB), then re-picks each pair's
// peak within 2 samples of the solution's lag and solves again (multipath: a pair whose pick
// is off the solution by more than 3 sigma and 1.5 samples is left out of the solve, the
// consensus subset, keeping at least 3 pairs). The mode's score is the normalised spectrum at the
// solution, summed over all usable pairs; a mode within 3 position standard deviations of a
// stronger one, by each one's own covariance, is merged into it. The solve is kept inside the
// bounds (projected) and within 3 radii of the centre; a solution beyond 1.5 x the radius is
// parked on the sphere in its direction (its spread across the bearing scaled to the radius,
// along it the radius), and two parked within one search direction's radius are one mode.
// Every mode within mode_margin sqrt(P) of the best survives (a 4-sensor array's two exact
// TDOA solutions score alike and both survive), at most max_modes, strongest first, each
// with its fix covariance (H^T W H)^-1.
//
// Cross pairs. When the measurement holds pairs without the reference (Measurement::cross_pairs,
// GccOptions::cross_pairs_max_sensors), the spatial spectrum sums them too, each at the lag
// lag_b - lag_a its position predicts: cell bounds, mode scores, the mode margin and the
// presence statistics count every usable pair (P above is then reference plus cross pairs),
// and so does the solve: a cross pair's pick is a residual of lag_b - lag_a, its gradient the
// difference of its sensors' reference rows, in the weighted least squares, the consensus
// subset and the variance factor alike. The count of lag combinations M uses the reference
// pairs. Why: a 4-sensor array's three reference pairs have an exact solution through any one
// pair's wrong peak (an echo's cross term, crosstalk, noise), which scores as well as the
// truth; the cross pairs read low there (acquisition_test: crosstalk on one pair, best mode
// 1.7 sd from the truth with them, 2200 sd without). And where one reference pair hears
// nothing (tonal sidelobes, a lost path) two reference pairs cannot fix a position, while the
// cross pairs holding its sensor can (acquisition_test: no mode from the reference pairs
// alone, 3.5 cm off with the cross pairs). They cannot tell apart what every pair agrees on:
// a 4-sensor array's second exact solution, or one channel's echo louder than its direct path.
//
// Earlier arrivals. An echo arrives after its direct path. Where one channel's echo is louder
// than its direct path, every pair holding that channel peaks on the echo, the reference and
// cross pairs agree on a position that is not the source, and the truth (the other pairs'
// peaks plus the weaker direct path) scores lower, by more than the margin at any useful
// SNR (campaign scene 16000131: 62.9 against 55.0 over 6 pairs). So, for each mode within the
// margin and each sensor, the shift of that sensor's arrival to an earlier time is sought:
// out of the main lobe, the shift whose sum over the sensor's usable pairs most exceeds its
// mirror image about the lobe's top (a source's GCC is symmetric about its peak, so sidelobes
// read alike on both sides), by at least 3 sqrt(pairs), with every one of those pairs reading
// at least 3 (a peak, not noise). Where exactly one sensor has one (an echo
// delayed alike at every sensor gives each channel an earlier cross term), the position is
// solved as above from the shifted lags, and its modes (flagged earlier_arrival) survive
// whatever their score: the tracker starts on both, and the motion decides. It needs a cross
// pair holding the sensor (a shift of one channel moves one reference pair alone, or, for the
// reference sensor, all of them alike: nothing confirms it).
//
// Open curves. Three picks always have an exact solution, and a pick at noise height is
// anywhere in its window, not where its curvature says: where a mode's consensus holds only
// two pairs whose picks stand clear of noise (>= 4.5, which noise reaches in a window of
// 10^4 independent lags about once in 30), its position along the curve those two leave open
// is unknown (campaign scene 15000105: a tonal source heard by 2 of 6 pairs, the first mode
// 7 m along that curve from the source with a 0.19 m spread). Such a mode carries up to 9
// points spread evenly along the curve (traced in steps of radius/16), so that a tracker
// starts along all of it and the motion and later frames decide.
//
// Presence (presence.h): statistic = best mode's score / sqrt(P) (with no mode solved, the
// sum of each pair's largest value / sqrt(P), which no position can exceed; never present
// then); the combinations the
// search chose from are M = min(prod_p W_p, 8 max_p W_p^3) for lag windows of W_p lags (a
// position has 3 degrees of freedom). Around a track, the per-pair windows are
// +-(3 sqrt(J_p C J_p^T) fs + 1) lags about the track's predicted lags (C its position
// covariance; a cross pair's J is J_b - J_a) and M = prod_p W_p over every usable pair.
//
// Cost: (cells x (sensors + pairs)) + refinements x ~10 solves over every pair, plus the earlier arrivals'
// modes x sensors x (lag window) x (pairs per sensor) field reads; ~1-3 ms for the default
// grid on one core. Not thread-safe; one per session.
#pragma once

#include <limits>
#include <vector>

#include "engine/acquisition/lag_field.h"
#include "engine/array/array_geometry.h"
#include "engine/core/measurement.h"
#include "engine/core/status.h"
#include "engine/core/types.h"

namespace localizer::engine {

struct AcquisitionOptions {
  Vec3 bounds_min_m = Vec3::Constant(-std::numeric_limits<double>::infinity());
  Vec3 bounds_max_m = Vec3::Constant(std::numeric_limits<double>::infinity());
  double search_radius_m = 0.0;  // 0: 10 apertures
  double false_alarm = 1e-3;     // per frame, in (0, 0.1]
  int max_modes = 4;             // in [1, 16]
  double mode_margin = 3.0;      // modes within this x sqrt(P) of the best's score survive
  int azimuth_cells = 32;
  int polar_cells = 16;
  int range_cells = 12;
  int refinement_budget = 64;    // cells refined at most
  bool earlier_arrivals = true;  // each channel's earlier arrival is solved too (above)

  Status Validate() const;
};

// A point of an open curve (PositionMode::open_curve) with its spread: across the curve the
// pairs that fix it, along it half the spacing between points.
struct CurvePoint {
  Vec3 position_m = Vec3::Zero();
  Mat3 covariance_m2 = Mat3::Identity();
};

// One position hypothesis.
struct PositionMode {
  Vec3 position_m = Vec3::Zero();
  Mat3 covariance_m2 = Mat3::Identity();
  double score = 0.0;  // normalised spatial spectrum at the position, summed over pairs
  int pairs_used = 0;  // pairs in the consensus subset of its solve
  // Found from a stronger mode as one channel's earlier arrival: kept whatever its score.
  bool earlier_arrival = false;
  // Where only two of the solve's pairs read clear of noise (Open curves, above): points along
  // the curve those two leave open, within 1.5 search radii and the bounds, the solution
  // among them. Empty otherwise. A tracker starts on all of them.
  std::vector<CurvePoint> open_curve;
};

struct PresenceResult {
  bool present = false;
  double statistic = 0.0;  // z
  double threshold = 0.0;  // t
  // Around only: sum over pairs of each pair's largest normalised value anywhere in its
  // window, / sqrt(P). A track that explains the data as well as anything could scores near
  // it; far below (an echo aside), something else explains the frame better.
  double unconstrained = 0.0;
};

struct AcquisitionResult {
  PresenceResult presence;
  std::vector<PositionMode> modes;  // strongest first; empty when none could be solved
};

class Acquisition {
 public:
  // INVALID_ARGUMENT naming the option.
  static StatusOr<Acquisition> Create(const ArrayGeometry& array, const AcquisitionOptions& options);

  // A moving array: search about its new pose.
  void SetArray(const ArrayGeometry& array) { array_ = array; }
  // The whole plausible volume.
  AcquisitionResult Search(const Measurement& m);
  // Presence near a track: position and its covariance (m, m^2).
  PresenceResult Around(const Measurement& m, const Vec3& position_m, const Mat3& covariance_m2);
  // On the field of the last Search or Around: the one channel whose strongest arrival at
  // `at_m` follows an earlier one that every pair holding it reads (above), and the
  // reference pairs' lags with that channel's earlier arrival. False when no channel, or more
  // than one, has such an arrival (a common echo delay gives every channel one), or the field
  // holds no cross pairs.
  bool EarlierArrival(const Vec3& at_m, std::vector<double>* reference_lags) const;
  // The field built for the last Search or Around (the same measurement).
  const LagField& field() const { return field_; }
  const AcquisitionOptions& options() const { return options_; }
  double search_radius_m() const;

 private:
  Acquisition(const ArrayGeometry& array, const AcquisitionOptions& options);
  struct Direction {
    Vec3 unit = Vec3::Zero();
    double angular_radius_rad = 0.0;
    double chord_per_range = 0.0;  // 2 sin(angular radius / 2): the cell's half-width per metre of range
  };
  // Picks, solves and scores from `start_m` (above); lo/hi: each field pair's lag window
  // (reference pairs first; cross pairs beyond their sizes are neither picked nor solved).
  bool Refine(const Vec3& start_m, const std::vector<double>& lo, const std::vector<double>& hi,
              PositionMode* mode) const;
  bool InBounds(const Vec3& p) const;
  double Score(const Vec3& p) const;
  // Field pair q >= reference_pairs() (a cross pair (a, b)): its lag from the reference
  // pairs' lags, lag_b - lag_a.
  double CrossLag(int q, const Eigen::VectorXd& pair_lags) const;
  // Its gradient from the reference pairs' (rows of pair_jacobian), row_b - row_a.
  Eigen::RowVector3d CrossGradient(int q, const Eigen::MatrixXd& pair_jacobian) const;
  // `sensor`'s earlier arrival at a position (above): the reference pairs' lags with that
  // sensor's arrival moved to it. False when there is none or no cross pair to confirm it.
  bool ChannelEarlierArrival(const Vec3& at_m, int sensor, std::vector<double>* reference_lags) const;
  // Points along the curve where field pairs pair[0] and pair[1] read lag[i] (sigma[i], samples),
  // from `on_m` (on it) both ways, within 1.5 search radii and the bounds (Open curves).
  std::vector<CurvePoint> OpenCurve(const Vec3& on_m, const int pair[2], const double lag[2],
                                    const double sigma[2]) const;

  ArrayGeometry array_;
  AcquisitionOptions options_;
  std::vector<Direction> directions_;
  LagField field_;
  const Measurement* measurement_ = nullptr;  // during Search only
};

}  // namespace localizer::engine
