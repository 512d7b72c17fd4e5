#include "engine/tws/tws_tracker.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <string>

#include "engine/tws/assignment.h"
#include "engine/tws/chi_square.h"
#include "engine/tws/clustering.h"
#include "engine/tws/cv_kalman.h"
#include "engine/tws/point_grid.h"
#include "engine/tws/polar_conversion.h"

namespace localizer::engine::tws {
namespace {

template <int D>
class TrackerImpl final : public TwsTracker {
  using K = Cv<D>;
  using State = typename K::State;
  using Cov = typename K::Cov;
  using Pos = typename K::Pos;
  using PosCov = typename K::PosCov;
  using Gain = typename K::Gain;

  struct Plot {
    Pos z;
    PosCov r;
  };
  struct Track {
    uint64_t id = 0;
    State x;
    Cov p;
    Gain last_gain = Gain::Zero();
    bool have_last_gain = false;
    // Steady-state form: frozen gain, its predicted and updated covariances, its dt.
    bool frozen = false;
    Gain frozen_gain;
    Cov frozen_predicted, frozen_updated;
    double frozen_dt = 0.0;
    uint32_t history = 0;  // bit 0: the latest scan brought a plot
    int age = 0;           // scans since initiation, the initiating one counting 1
    int hits = 0;
    int misses = 0;  // in a row
    bool confirmed = false;
    int plot = -1;  // this scan's plot, -1 none
  };
  struct Edge {
    int track;  // index into the stage's track list
    int plot;
    double d2;
  };

 public:
  explicit TrackerImpl(const TwsOptions& options)
      : options_(options),
        gate_(ChiSquareQuantile(D, options.gate_probability)),
        q_(options.accel_noise_mps2 * options.accel_noise_mps2),
        window_mask_(options.confirm_window >= 32 ? 0xffffffffu
                                                  : (1u << options.confirm_window) - 1u) {}

  Status Process(const Scan& scan, ScanSummary* summary) override {
    LOCALIZER_RETURN_IF_ERROR(CheckTime(scan.time_s));
    for (size_t i = 0; i < scan.detections.size(); ++i) {
      const Detection& d = scan.detections[i];
      // The message is built only on failure: no allocation per plot on the hot path.
      auto where = [i] { return "detections[" + std::to_string(i) + "]"; };
      if (!std::isfinite(d.range_m) || d.range_m <= 0.0)
        return InvalidArgument(where() + ".range_m is " + std::to_string(d.range_m) + ", must be finite and > 0");
      if (!std::isfinite(d.bearing_rad)) return InvalidArgument(where() + ".bearing_rad is not finite");
      if (d.elevation_rad && !std::isfinite(*d.elevation_rad))
        return InvalidArgument(where() + ".elevation_rad is not finite");
      if (D == 3 && !d.elevation_rad)
        return InvalidArgument(where() + ".elevation_rad is missing; a 3-D tracker needs it");
    }
    if (!scan.sensor_position_m.allFinite()) return InvalidArgument("sensor_position_m is not finite");
    plots_.resize(scan.detections.size());
    for (size_t i = 0; i < scan.detections.size(); ++i) {
      const Detection& d = scan.detections[i];
      if constexpr (D == 2) {
        const double ground = d.elevation_rad ? d.range_m * std::cos(*d.elevation_rad) : d.range_m;
        const Converted2 c = ConvertPolar(ground, d.bearing_rad, options_.noise, options_.conversion);
        plots_[i].z = c.position_m + scan.sensor_position_m.head<2>();
        plots_[i].r = c.covariance_m2;
      } else {
        const Converted3 c = ConvertSpherical(d.range_m, d.bearing_rad, *d.elevation_rad,
                                              options_.noise, options_.conversion);
        plots_[i].z = c.position_m + scan.sensor_position_m;
        plots_[i].r = c.covariance_m2;
      }
    }
    Run(scan.time_s, summary);
    return Status::Ok();
  }

  Status ProcessCartesian(double time_s, const std::vector<CartesianPlot>& plots,
                          ScanSummary* summary) override {
    LOCALIZER_RETURN_IF_ERROR(CheckTime(time_s));
    for (size_t i = 0; i < plots.size(); ++i) {
      if (!plots[i].position_m.allFinite() || !plots[i].covariance_m2.allFinite())
        return InvalidArgument("plots[" + std::to_string(i) + "] is not finite");
    }
    plots_.resize(plots.size());
    for (size_t i = 0; i < plots.size(); ++i) {
      plots_[i].z = plots[i].position_m.template head<D>();
      plots_[i].r = plots[i].covariance_m2.template topLeftCorner<D, D>();
    }
    Run(time_s, summary);
    return Status::Ok();
  }

  void Tracks(std::vector<TrackReport>* out, bool include_tentative) const override {
    out->clear();
    for (const Track& t : tracks_) {
      if (!t.confirmed && !include_tentative) continue;
      TrackReport r;
      r.id = t.id;
      r.status = !t.confirmed ? TrackStatus::kTentative
                              : (t.misses > 0 ? TrackStatus::kCoasting : TrackStatus::kConfirmed);
      r.position_m.head<D>() = t.x.template head<D>();
      r.velocity_mps.head<D>() = t.x.template tail<D>();
      r.covariance.template topLeftCorner<D, D>() = t.p.template topLeftCorner<D, D>();
      r.covariance.template block<D, D>(0, 3) = t.p.template topRightCorner<D, D>();
      r.covariance.template block<D, D>(3, 0) = t.p.template bottomLeftCorner<D, D>();
      r.covariance.template block<D, D>(3, 3) = t.p.template bottomRightCorner<D, D>();
      r.hits = t.hits;
      r.consecutive_misses = t.misses;
      r.time_s = last_time_;
      r.steady_state = t.frozen;
      out->push_back(r);
    }
    // tracks_ is kept in order of initiation (deletion preserves order), so of id.
  }

  const TwsOptions& options() const override { return options_; }
  int track_count() const override { return static_cast<int>(tracks_.size()); }
  int64_t total_track_updates() const override { return total_updates_; }

 private:
  Status CheckTime(double t) const {
    if (!std::isfinite(t)) return InvalidArgument("time_s is not finite");
    if (have_time_ && !(t > last_time_))
      return InvalidArgument("time_s is " + std::to_string(t) + ", not after the previous scan's " +
                             std::to_string(last_time_));
    return Status::Ok();
  }

  void Run(double t, ScanSummary* summary) {
    ScanSummary s;
    s.plots = static_cast<int>(plots_.size());
    const double dt = have_time_ ? t - last_time_ : 0.0;
    s.track_updates = static_cast<int64_t>(tracks_.size());
    total_updates_ += s.track_updates;
    Predict(dt);
    plot_xy_.resize(plots_.size());
    max_r_diag_.setZero();
    for (size_t j = 0; j < plots_.size(); ++j) {
      plot_xy_[j] = plots_[j].z.template head<2>();
      max_r_diag_ = max_r_diag_.cwiseMax(plots_[j].r.diagonal());
    }
    grid_.Build(plot_xy_);
    plot_taken_.assign(plots_.size(), 0);
    for (Track& tr : tracks_) tr.plot = -1;
    // Confirmed tracks first, then tentative ones on what is left.
    for (int stage = 0; stage < 2; ++stage) {
      stage_tracks_.clear();
      for (int i = 0; i < static_cast<int>(tracks_.size()); ++i) {
        if (tracks_[i].confirmed == (stage == 0)) stage_tracks_.push_back(i);
      }
      Associate(s);
    }
    for (Track& tr : tracks_) {
      tr.history <<= 1;
      ++tr.age;
      if (tr.plot >= 0) {
        UpdateTrack(tr, plots_[tr.plot], dt);
        tr.history |= 1u;
        ++tr.hits;
        tr.misses = 0;
        ++s.assigned;
      } else {
        ++tr.misses;
        if (tr.frozen) tr.frozen = false;  // the steady state assumed a plot every scan
        tr.have_last_gain = false;
      }
    }
    Manage(s);
    Initiate(dt, s);
    for (const Track& tr : tracks_) (tr.confirmed ? s.confirmed : s.tentative) += 1;
    last_time_ = t;
    have_time_ = true;
    if (summary) *summary = s;
  }

  void Predict(double dt) {
    if (dt <= 0.0) return;
    for (Track& tr : tracks_) {
      K::PredictState(tr.x, dt);
      if (tr.frozen && std::abs(dt - tr.frozen_dt) <= 1e-9 * tr.frozen_dt) {
        tr.p = tr.frozen_predicted;
      } else {
        tr.frozen = false;
        K::PredictCov(tr.p, dt, q_);
      }
    }
  }

  void UpdateTrack(Track& tr, const Plot& plot, double dt) {
    if (tr.frozen) {
      K::UpdateConstantGain(tr.x, tr.frozen_gain, plot.z);
      tr.p = tr.frozen_updated;
      return;
    }
    const Cov predicted = tr.p;
    const Gain gain = K::Update(tr.x, tr.p, plot.z, plot.r);
    if (options_.filter == FilterForm::kSteadyState && tr.have_last_gain && dt > 0.0) {
      const double change = (gain - tr.last_gain).cwiseAbs().maxCoeff();
      if (change <= options_.steady_state_tolerance * gain.cwiseAbs().maxCoeff()) {
        tr.frozen = true;
        tr.frozen_gain = gain;
        tr.frozen_predicted = predicted;
        tr.frozen_updated = tr.p;
        tr.frozen_dt = dt;
      }
    }
    tr.last_gain = gain;
    tr.have_last_gain = true;
  }

  // Gates the stage's tracks against the untaken plots, clusters, assigns.
  void Associate(ScanSummary& s) {
    edges_.clear();
    const int n_tracks = static_cast<int>(stage_tracks_.size());
    for (int local = 0; local < n_tracks; ++local) {
      const Track& tr = tracks_[stage_tracks_[local]];
      const Pos p = tr.x.template head<D>();
      const PosCov a = tr.p.template topLeftCorner<D, D>();
      // Coarse: |nu_k| <= sqrt(g S_kk) is necessary for nu^T S^-1 nu <= g; bound S_kk by the
      // scan's largest R_kk.
      const double hx = std::sqrt(gate_ * (a(0, 0) + max_r_diag_(0)));
      const double hy = std::sqrt(gate_ * (a(1, 1) + max_r_diag_(1)));
      grid_.Query(p(0) - hx, p(0) + hx, p(1) - hy, p(1) + hy, [&](int j) {
        if (plot_taken_[j]) return;
        const Plot& plot = plots_[j];
        const PosCov sm = a + plot.r;
        const Pos nu = plot.z - p;
        for (int k = 0; k < D; ++k) {
          if (nu(k) * nu(k) > gate_ * sm(k, k)) return;  // the exact per-axis bound
        }
        const double d2 = nu.dot(sm.inverse() * nu);
        if (d2 <= gate_) edges_.push_back({local, j, d2});
      });
    }
    if (edges_.empty()) return;
    // Connected components: track nodes 0..n_tracks-1, plot nodes n_tracks + j.
    const int n_plots = static_cast<int>(plots_.size());
    uf_.Reset(n_tracks + n_plots);
    for (const Edge& e : edges_) uf_.Union(e.track, n_tracks + e.plot);
    cluster_of_root_.assign(n_tracks + n_plots, -1);
    int n_clusters = 0;
    for (const Edge& e : edges_) {
      const int root = uf_.Find(e.track);
      if (cluster_of_root_[root] < 0) cluster_of_root_[root] = n_clusters++;
    }
    // Edges grouped by cluster (counting sort).
    cluster_start_.assign(n_clusters + 1, 0);
    edge_cluster_.resize(edges_.size());
    for (size_t k = 0; k < edges_.size(); ++k) {
      edge_cluster_[k] = cluster_of_root_[uf_.Find(edges_[k].track)];
      ++cluster_start_[edge_cluster_[k] + 1];
    }
    for (int c = 0; c < n_clusters; ++c) cluster_start_[c + 1] += cluster_start_[c];
    sorted_edges_.resize(edges_.size());
    fill_.assign(cluster_start_.begin(), cluster_start_.end() - 1);
    for (size_t k = 0; k < edges_.size(); ++k) sorted_edges_[fill_[edge_cluster_[k]]++] = edges_[k];
    s.clusters += n_clusters;
    local_index_.assign(n_tracks + n_plots, -1);
    for (int c = 0; c < n_clusters; ++c) {
      const Edge* begin = sorted_edges_.data() + cluster_start_[c];
      const Edge* end = sorted_edges_.data() + cluster_start_[c + 1];
      SolveCluster(begin, end, n_tracks, s);
    }
  }

  void SolveCluster(const Edge* begin, const Edge* end, int n_tracks, ScanSummary& s) {
    rows_.clear();
    cols_.clear();
    for (const Edge* e = begin; e != end; ++e) {
      if (local_index_[e->track] < 0) {
        local_index_[e->track] = static_cast<int>(rows_.size());
        rows_.push_back(e->track);
      }
      if (local_index_[n_tracks + e->plot] < 0) {
        local_index_[n_tracks + e->plot] = static_cast<int>(cols_.size());
        cols_.push_back(e->plot);
      }
    }
    s.largest_cluster = std::max(s.largest_cluster, static_cast<int>(rows_.size()));
    if (rows_.size() == 1) {  // every plot of the cluster sees this track only
      const Edge* best = begin;
      for (const Edge* e = begin; e != end; ++e) {
        if (e->d2 < best->d2) best = e;
      }
      Take(best->track, best->plot);
    } else {
      const int nr = static_cast<int>(rows_.size()), nc = static_cast<int>(cols_.size());
      cost_.assign(static_cast<size_t>(nr) * nc, kForbidden);
      for (const Edge* e = begin; e != end; ++e) {
        cost_[static_cast<size_t>(local_index_[e->track]) * nc + local_index_[n_tracks + e->plot]] = e->d2;
      }
      miss_.assign(nr, gate_);
      col_for_row_.resize(nr);
      solver_.SolveGnn(cost_.data(), nr, nc, miss_.data(), col_for_row_.data());
      for (int r = 0; r < nr; ++r) {
        if (col_for_row_[r] >= 0) Take(rows_[r], cols_[col_for_row_[r]]);
      }
    }
    for (int r : rows_) local_index_[r] = -1;
    for (int c : cols_) local_index_[n_tracks + c] = -1;
  }

  void Take(int local_track, int plot) {
    tracks_[stage_tracks_[local_track]].plot = plot;
    plot_taken_[plot] = 1;
  }

  void Manage(ScanSummary& s) {
    const int m = options_.confirm_hits, n = options_.confirm_window;
    const double max_var = options_.max_position_sigma_m * options_.max_position_sigma_m;
    size_t kept = 0;
    for (size_t i = 0; i < tracks_.size(); ++i) {
      Track& tr = tracks_[i];
      const int hits_in_window = std::popcount(tr.history & window_mask_);
      if (!tr.confirmed && hits_in_window >= m) tr.confirmed = true;
      bool remove = false;
      if (!tr.confirmed) {
        const int scans_left = std::max(0, n - tr.age);
        remove = hits_in_window + scans_left < m;
      } else {
        remove = tr.misses >= options_.max_coast_scans;
      }
      if (tr.p.template topLeftCorner<D, D>().diagonal().maxCoeff() > max_var) remove = true;
      if (remove) {
        ++s.deleted;
        continue;
      }
      if (kept != i) tracks_[kept] = tr;
      ++kept;
    }
    tracks_.resize(kept);
  }

  void StartTrack(const State& x, const Cov& p, int hits_so_far) {
    Track tr;
    tr.id = next_id_++;
    tr.x = x;
    tr.p = p;
    tr.age = hits_so_far;
    tr.hits = hits_so_far;
    tr.history = hits_so_far >= 2 ? 3u : 1u;
    tr.confirmed = std::popcount(tr.history & window_mask_) >= options_.confirm_hits;
    tracks_.push_back(tr);
  }

  void Initiate(double dt, ScanSummary& s) {
    const int room = options_.max_tracks - static_cast<int>(tracks_.size());
    int started = 0;
    if (options_.initiation == Initiation::kOnePoint) {
      for (size_t j = 0; j < plots_.size() && started < room; ++j) {
        if (plot_taken_[j]) continue;
        State x = State::Zero();
        x.template head<D>() = plots_[j].z;
        Cov p = Cov::Zero();
        p.template topLeftCorner<D, D>() = plots_[j].r;
        p.template bottomRightCorner<D, D>() =
            PosCov::Identity() * options_.initial_speed_sigma_mps * options_.initial_speed_sigma_mps;
        StartTrack(x, p, 1);
        ++started;
      }
    } else {
      // Two-point: pair each leftover plot with the nearest leftover of the previous scan
      // within max_speed dt (plus 3 sigma of both plots); the rest wait for the next scan.
      candidate_grid_.Build(candidate_xy_);
      candidate_used_.assign(candidates_.size(), 0);
      next_candidates_.clear();
      for (size_t j = 0; j < plots_.size(); ++j) {
        if (plot_taken_[j]) continue;
        const Plot& plot = plots_[j];
        int best = -1;
        double best_d2 = 0.0;
        if (dt > 0.0 && !candidates_.empty() && started < room) {
          const double reach = options_.max_speed_mps * dt +
                               3.0 * std::sqrt(plot.r.trace() + max_candidate_r_trace_);
          const Pos z = plot.z;
          candidate_grid_.Query(z(0) - reach, z(0) + reach, z(1) - reach, z(1) + reach, [&](int c) {
            if (candidate_used_[c]) return;
            const double d2 = (candidates_[c].z - z).squaredNorm();
            if (d2 <= reach * reach && (best < 0 || d2 < best_d2)) {
              best = c;
              best_d2 = d2;
            }
          });
        }
        if (best < 0) {
          next_candidates_.push_back(plot);
          continue;
        }
        candidate_used_[best] = 1;
        const Plot& first = candidates_[best];
        State x;
        x.template head<D>() = plot.z;
        x.template tail<D>() = (plot.z - first.z) / dt;
        Cov p;
        p.template topLeftCorner<D, D>() = plot.r;
        p.template topRightCorner<D, D>() = plot.r / dt;
        p.template bottomLeftCorner<D, D>() = plot.r / dt;
        p.template bottomRightCorner<D, D>() = (plot.r + first.r) / (dt * dt);
        StartTrack(x, p, 2);
        ++started;
      }
      candidates_.swap(next_candidates_);
      candidate_xy_.resize(candidates_.size());
      max_candidate_r_trace_ = 0.0;
      for (size_t c = 0; c < candidates_.size(); ++c) {
        candidate_xy_[c] = candidates_[c].z.template head<2>();
        max_candidate_r_trace_ = std::max(max_candidate_r_trace_, candidates_[c].r.trace());
      }
    }
    s.initiated = started;
  }

  const TwsOptions options_;
  const double gate_;
  const double q_;
  const uint32_t window_mask_;
  std::vector<Track> tracks_;
  uint64_t next_id_ = 1;
  double last_time_ = 0.0;
  bool have_time_ = false;
  int64_t total_updates_ = 0;
  // Per-scan work arrays, kept between scans.
  std::vector<Plot> plots_;
  std::vector<Eigen::Vector2d> plot_xy_;
  Eigen::Matrix<double, D, 1> max_r_diag_;
  std::vector<char> plot_taken_;
  PointGrid grid_;
  std::vector<int> stage_tracks_;
  std::vector<Edge> edges_, sorted_edges_;
  UnionFind uf_;
  std::vector<int> cluster_of_root_, cluster_start_, edge_cluster_, fill_, local_index_;
  std::vector<int> rows_, cols_, col_for_row_;
  std::vector<double> cost_, miss_;
  AssignmentSolver solver_;
  // Two-point initiation: the previous scan's leftover plots.
  std::vector<Plot> candidates_, next_candidates_;
  std::vector<Eigen::Vector2d> candidate_xy_;
  std::vector<char> candidate_used_;
  double max_candidate_r_trace_ = 0.0;
  PointGrid candidate_grid_;
};

}  // namespace

StatusOr<std::unique_ptr<TwsTracker>> TwsTracker::Create(const TwsOptions& options) {
  LOCALIZER_RETURN_IF_ERROR(options.Validate());
  if (options.dimensions == 2) return std::unique_ptr<TwsTracker>(new TrackerImpl<2>(options));
  return std::unique_ptr<TwsTracker>(new TrackerImpl<3>(options));
}

}  // namespace localizer::engine::tws
