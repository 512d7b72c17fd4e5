// Direction of arrival by steered response power with the phase transform (SRP-PHAT): the
// GCC-PHAT of every pair of sensors (pair_spectra.h), summed at the lags a far-field source
// in each direction would give, searched coarse to fine; several sources per frame.
//
// Model. A plane wave from unit direction u (pointing from the array to the source) reaches
// sensor m at t(m) = -m.u / c, so pair (i, j) peaks at lag_p(u) = D_p.u samples with
// D_p = -(m_i - m_j) fs / c. The spectrum
//     z(u) = sum_p n_p(lag_p(u)) / sqrt(P)          (n_p: pair p's normalised GCC)
// is ~N(0, 1) at any one direction when the frame holds only noise, and ~sqrt(P) times the
// pairs' mean peak height over their noise for a source (tens to hundreds).
//
// What is searched is what the array observes (array_shape.h):
//   volumetric  the sphere of directions;
//   planar      the hemisphere on the array normal's side: the other hemisphere gives the
//               same lags. With `source_side` (sources lie where u.side > 0, side not in
//               the array plane) the direction on that side is reported; without it the peak
//               is flagged mirror_ambiguous and both candidates are given;
//   linear      the cone angle theta in [0, pi] between u and the array axis (u.axis =
//               cos theta); the direction itself is not observable (NaN).
//
// Search, per source. A leaf is a cell that spans at most half a sample of lag on every
// pair (radius 0.5 / max_p g_p). When at most 8192 leaves cover the domain (a sphere needs
// (6 g)^2 of them, g = max_p g_p: arrays whose longest pair spans at most 15 samples, 32 cm
// at 16 kHz in air), the roots are the leaves: a plain grid, each scored by z at its centre. Otherwise, branch and
// bound (as acquisition.h does over positions) from 8192 roots (about half of them for a
// planar array's hemisphere). The roots count against cell_budget, so at the default budget
// (4096) no cell is split: Newton's method refines the root with the largest bound
// (search_starts more of them, option). Measured on a 0.5-m tetrahedron at 16 kHz with two
// sources (ACCURACY.md, "Large arrays"): one start left frames with no peak though both
// sources held z ~20; splitting to 4096 cells past the roots cost 30-80 % more per frame and
// found fewer sources near the array; 8 starts found 17 % more source-frames within 10
// degrees for 6-10 % more, but changed which of two steady sources leads, which the tracker's
// start rules turn on (direction_tracker.h, "Co-leaders"), so it is not the default yet
// (tests/bench/two_source_report measures it; AudioSessionConfig::direction_search_starts).
// Roots are Fibonacci-lattice caps on the sphere (those reaching the searched hemisphere
// when planar), or arcs of theta. A cell of angular radius r
// centred on c cannot hold a lag further than g_p r from lag_p(c), g_p = |D_p| (|D_p.axis|
// for arcs), so
//     U(cell) = sum_p max{ n_p(l) : |l - lag_p(c)| <= g_p r + 0.5 } / sqrt(P)
// bounds z over it. Cells are split in decreasing U (4 caps of radius r / sqrt(2), or 2
// arcs) down to leaves (scored by z at their centre from the field), stopping when the best
// leaf beats every open bound, or after cell_budget cells. The best leaf is refined by Newton's method on the exact
// spectrum (PairSpectra::At, no lag quantisation).
//
// Several sources: after each one, its pure-delay component is removed from every pair's
// spectrum (PairSpectra::RemoveDelay: the peak and its sidelobes go, other sources stay)
// and the search runs again on the residual, until max_sources are found or the best peak
// falls below the threshold. A residual whose every pair's largest sample, summed, times
// the band's interpolation margin (below) stays under the threshold cannot hold a source, and
// is not searched: the refined statistic reads the continuous GCC, which can exceed its
// samples by at most 1 / (the band's mean cos(2 pi f / 2), a peak half a sample off), and
// 10 % more. On the 4-microphone board with one talker the residual's bound is 0.46-0.57 of
// the threshold, so every empty search is skipped; on the circle and line it is not.
// Each earlier source was refined with the later ones still in
// its spectrum, which biases it, and a removal at a biased lag leaves structured residue
// that the next search takes for a source: so after each new source, every source found is
// put back, refined among the others' residual and removed again (2 passes); one whose
// statistic falls below the threshold there is not reported. The threshold is
//     t = Q^-1(false_alarm / M),  M = the leaf cells that tile the domain,
// a union bound over the directions the search chooses from (presence.h), so a frame of
// noise reports a source with probability <= false_alarm per search.
// Limits, measured in tests/doa/srp_phat_test.cc: PHAT's cross-spectrum is quadratic in the
// signals, so a source 10 dB below another holds about a tenth of it (z ~ 0.1 x the loud
// one's). Without the re-estimation, two equal sources left a spurious peak (up to 0.36 x
// the weaker one's z) in every frame; with it, none in 20 frames.
//
// Cost per frame: PairSpectra's transforms, plus per source a search of typically tens to a
// few hundred cells of P lookups each and one refinement of a few probes of P x B complex
// multiplies (B in-band bins), plus the re-estimations when a frame holds several sources
// (2 passes over the sources found) and P inverse FFTs per search after the first. Measured
// in BENCHMARKS.md (doa_bench): 46-53 us for one source on a 4-microphone board (a 2-vCPU
// VM, 2026-12-03). Not thread-safe.
#pragma once

#include <complex>
#include <limits>
#include <vector>

#include "engine/acquisition/lag_field.h"
#include "engine/core/measurement.h"
#include "engine/core/status.h"
#include "engine/core/types.h"
#include "engine/doa/array_shape.h"
#include "engine/doa/pair_spectra.h"

namespace localizer::engine {

struct SrpOptions {
  double sample_rate_hz = 16000.0;
  double sound_speed_mps = 343.0;
  int frame_samples = 512;
  // Samples between the starts of consecutive frames (0: frames do not overlap). Only for
  // DirectionPeak::rise, measured against the last frame that does not overlap this one.
  int hop_samples = 0;
  double band_low_hz = 0.0;
  double band_high_hz = 0.0;  // 0: the Nyquist frequency
  int max_sources = 4;        // in [1, 16]
  double false_alarm = 1e-3;  // per frame and source search, in (0, 0.1]
  // Planar arrays: sources lie where u.source_side > 0 (zero: not stated). Must not lie in
  // the array plane. Ignored for other shapes.
  Vec3 source_side = Vec3::Zero();
  int cell_budget = 4096;  // cells bounded per source search, the roots included, in [64, 2^20]
  // When the budget runs out before any leaf (at the default budget, always so for a large
  // array's 8192 roots: "Search" above), Newton's method starts from this many of the cells
  // with the largest bounds (skipping those beside an end point already reached) and the best
  // end point is kept; in [1, 64].
  int search_starts = 1;
  // A later source is reported only when its statistic is at least this share of the
  // frame's strongest (0: off, in [0, 1)). In a room, reflections are coherent sources in
  // other directions that pass the noise threshold; a source 10 dB below another has ~0.1
  // of its statistic (srp_phat.h, "Limits"), so a share above that loses such sources.
  double min_relative_statistic = 0.0;
  // Keep each frame's field before any source is removed (whole_field()), for near-field
  // fits (near_field.h); off, a frame copies nothing.
  bool keep_whole_field = false;
  // Each pair's bins weighted by how little a room's diffuse sound correlates across it
  // (pair_spectra.h, "Diffuse weighting"); false: every in-band bin alike.
  bool diffuse_weighting = false;
  // Each frame's bins weighted by their share of signal (pair_spectra.h, "Signal weighting");
  // false: every in-band bin alike (PHAT).
  bool signal_weighting = false;

  Status Validate() const;
};

// Whether an array of this shape weighs its bins by their signal (SrpOptions::signal_weighting)
// when its user does not say: planar and volumetric arrays do; linear ones do not, since a
// line resolves a talker's floor and ceiling images as sources of their own and the weighting
// lifts them with the talker (ACCURACY.md, "A talker's harmonics").
inline bool DefaultSignalWeighting(ArrayShape shape) { return shape != ArrayShape::kLinear; }

// One source heard in a frame.
struct DirectionPeak {
  static constexpr double kNan = std::numeric_limits<double>::quiet_NaN();
  // Unit vector from the array towards the source, in the sensors' frame; NaN for linear
  // arrays. azimuth = atan2(y, x), elevation = asin(z) (from the x-y plane towards +z).
  Vec3 direction = Vec3::Constant(kNan);
  double azimuth_rad = kNan;
  double elevation_rad = kNan;
  // Angle between the direction and the array axis, [0, pi]; linear arrays only.
  double cone_angle_rad = kNan;
  // Planar arrays without source_side: the mirror image across the array plane fits the
  // lags equally (NaN direction when not ambiguous).
  bool mirror_ambiguous = false;
  Vec3 mirror_direction = Vec3::Constant(kNan);
  double statistic = 0.0;  // z at the peak (after the removal of stronger sources)
  // z at the peak's direction in this frame's whole spectrum (no source removed) less z
  // there in the last frame that does not overlap it (hop_samples; 0 before the first such
  // frame): how much the direction rose.
  // A source that starts rises most at its own direction: its direct sound arrives first,
  // and each reflection is weaker than it (onset.h).
  double rise = 0.0;
  double previous_statistic = 0.0;  // z there in that earlier frame (rise = whole z now - this)
  double threshold = 0.0;           // t
  // The pairs' mean peak height over their noise-only deviation, 20 log10(z / sqrt(P)):
  // 0 dB is the noise level.
  double power_db = 0.0;
};

class SrpPhat {
 public:
  // INVALID_ARGUMENT naming the option or the sensors (array_shape.h, pair_spectra.h).
  static StatusOr<SrpPhat> Create(const std::vector<Vec3>& sensors_m, const SrpOptions& options);

  const ArrayShapeInfo& shape() const { return shape_; }
  const SrpOptions& options() const { return options_; }
  int pair_count() const { return spectra_.pair_count(); }
  double threshold() const { return threshold_; }  // t, the statistic a source must reach

  // Sources in the frame (sensors x frame_samples floats, channel-major), strongest first,
  // at most max_sources; empty when none passes the threshold. INVALID_ARGUMENT for a
  // non-finite sample.
  StatusOr<std::vector<DirectionPeak>> Analyse(const float* frame);

  // The last analysed frame's in-band power (PairSpectra::band_power): for onsets (onset.h).
  double band_power() const { return spectra_.band_power(); }
  // The pair spectra of the last analysed frame (near-field fits read its whole spectrum).
  const PairSpectra& spectra() const { return spectra_; }
  // The same, to remove chosen sources from (near-field fits of one source among several).
  // What the caller changes is what Statistic() reads until the next Analyse.
  PairSpectra& mutable_spectra() { return spectra_; }
  // With SrpOptions::keep_whole_field, the last analysed frame's GCC of every pair at
  // integer lags before any source was removed (PairSpectra::Analyse's field): near-field
  // fits' coarse search reads it. Empty otherwise.
  const Measurement& whole_field() const { return whole_field_; }

  // z at a direction (far-field lags; linear arrays read only u.axis) from the last
  // analysed frame's exact spectrum, less the sources removed before its last search (none
  // when max_sources is 1).
  double Statistic(const Vec3& direction) const;

 private:
  SrpPhat(const ArrayShapeInfo& shape, const SrpOptions& options, PairSpectra spectra);
  struct Cell {
    double bound = 0.0;
    Vec3 u = Vec3::Zero();   // sphere cells: the centre
    double theta_rad = 0.0;  // arcs: the centre
    double radius_rad = 0.0;
  };
  bool linear() const { return shape_.shape == ArrayShape::kLinear; }
  double Lag(int p, const Cell& cell) const;
  double Spread(int p, double radius_rad) const;  // g_p r
  double Bound(const Cell& cell) const;
  double Centre(const Cell& cell) const;  // z at the centre, from the field
  // Centre(roots_[r]) for every root into grid_sums_ (times sqrt(P)) from the grid's taps,
  // when every pair is usable: the same values. False when the grid has no taps.
  bool GridCentres();
  std::vector<Cell> Roots() const;  // computed once, into roots_
  void Split(const Cell& cell, std::vector<Cell>* children) const;
  bool Leaf(const Cell& cell) const;
  // The best cell; when the budget ran out before any leaf, starts_ gets the next
  // search_starts - 1 cells by bound.
  bool Search(Cell* best);
  std::vector<Cell> starts_;
  // Refines starts_ (Search's other cells) and returns the best end point of them and `best`
  // (already refined, at *statistic), which *statistic then holds.
  Cell RefineOtherStarts(Cell best, double* statistic);
  std::vector<Cell> ends_;                           // RefineOtherStarts' scratch: the end points
  double Apart(const Cell& a, const Cell& b) const;  // angle between centres (cone angles for arcs)
  struct Probe {
    double value = 0.0;  // sum_p R_p at the centre
    Eigen::Vector2d gradient = Eigen::Vector2d::Zero();
    Eigen::Matrix2d hessian = Eigen::Matrix2d::Zero();
    Eigen::Matrix<double, 3, 2> basis = Eigen::Matrix<double, 3, 2>::Zero();  // the step's axes
  };
  Probe ProbeAt(const Cell& cell) const;
  Cell Moved(const Cell& cell, const Probe& probe, const Eigen::Vector2d& step) const;
  // Newton's method on the exact spectrum from `cell`; *statistic = Exact(the result).
  Cell Refine(Cell cell, double* statistic) const;
  double Exact(const Cell& cell) const;                 // z from the exact (residual) spectrum
  double Whole(const Cell& cell, bool previous) const;  // z from a whole spectrum (PairSpectra::WholeAt)
  // The residual field's largest possible z anywhere: every pair's largest sample, summed
  // over pairs / sqrt(P), times interpolation_margin_.
  double FieldCeiling() const;
  // statistic_is_whole: the statistic is Whole(cell, false) (not recomputed).
  DirectionPeak Describe(const Cell& cell, double statistic, bool statistic_is_whole) const;

  ArrayShapeInfo shape_;
  SrpOptions options_;
  PairSpectra spectra_;
  std::vector<Vec3> lag_per_direction_;  // D_p, samples per unit of direction
  double max_spread_ = 0.0;              // max_p g_p
  double leaf_radius_rad_ = 0.0;
  int root_count_ = 0;
  std::vector<Cell> roots_;
  // A plain grid (roots are leaves): per pair and root (pair-major), LagField::At's reading
  // of the root's lag as w0 n_p[i0] + w1 n_p[i0 + 1] over the pair's samples padded with a 0
  // (fixed: the lags and the pairs' windows are). Outside the window w0 = w1 = 0; at its last
  // sample w1 = 0.
  std::vector<int> grid_index_;
  std::vector<double> grid_w0_, grid_w1_;
  std::vector<double> grid_samples_, grid_sums_;  // per frame: the padded samples, the roots' sums
  double root_radius_rad_ = 0.0;
  double threshold_ = 0.0;
  double interpolation_margin_ = 1.0;  // continuous GCC maximum / sampled maximum, at most (above)
  // Per source found in a frame (in the order found), per pair and in-band bin: what
  // RemoveDelay took. Kept across frames, so that a frame allocates nothing for it.
  std::vector<std::vector<std::vector<std::complex<double>>>> removed_;
  Measurement field_input_;
  Measurement whole_field_;  // field_input_ as Analyse left it (keep_whole_field only)
  LagField field_;
};

}  // namespace localizer::engine
