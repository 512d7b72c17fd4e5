#include "engine/tws/tws_tracker.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "engine/tws/associator.h"
#include "engine/tws/chi_square.h"
#include "engine/tws/deleter.h"
#include "engine/tws/gaussian.h"
#include "engine/tws/initiator.h"
#include "engine/tws/polar_conversion.h"
#include "engine/tws/track_history.h"
#include "engine/tws/updater.h"

namespace localizer::engine::tws {
namespace {

template <int D>
class TrackerImpl final : public TwsTracker {
  struct Track {
    FilterState<D> filter;  // first: no padding before its aligned members
    uint64_t id = 0;
    TrackHistory history;
    int measurement = -1;  // this scan's, -1 none
  };

 public:
  explicit TrackerImpl(const TwsOptions& options)
      : options_(options),
        updater_(options.updater()),
        associator_(ChiSquareQuantile(D, options.gate_probability), options.associator()),
        initiator_(options.initiator()),
        deleter_(options.deleter()) {}

  Status Process(const Scan& scan, ScanSummary* summary) override {
    LOCALIZER_RETURN_IF_ERROR(CheckPlotCount(scan.detections.size()));
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
    may_start_.assign(scan.detections.size(), 1);
    may_not_resume_.assign(scan.detections.size(), 0);
    for (size_t i = 0; i < scan.detections.size(); ++i) {
      const Detection& d = scan.detections[i];
      if constexpr (D == 2) {
        const double ground = d.elevation_rad ? d.range_m * std::cos(*d.elevation_rad) : d.range_m;
        const Converted2 c = ConvertPolar(ground, d.bearing_rad, options_.noise, options_.conversion);
        plots_[i].mean = c.position_m + scan.sensor_position_m.head<2>();
        plots_[i].covariance = c.covariance_m2;
      } else {
        const Converted3 c =
            ConvertSpherical(d.range_m, d.bearing_rad, *d.elevation_rad, options_.noise, options_.conversion);
        plots_[i].mean = c.position_m + scan.sensor_position_m;
        plots_[i].covariance = c.covariance_m2;
      }
    }
    Run(scan.time_s, summary);
    return Status::Ok();
  }

  Status ProcessCartesian(double time_s, const std::vector<CartesianPlot>& plots, ScanSummary* summary) override {
    LOCALIZER_RETURN_IF_ERROR(CheckPlotCount(plots.size()));
    LOCALIZER_RETURN_IF_ERROR(CheckTime(time_s));
    for (size_t i = 0; i < plots.size(); ++i) {
      if (!plots[i].position_m.allFinite() || !plots[i].covariance_m2.allFinite())
        return InvalidArgument("plots[" + std::to_string(i) + "] is not finite");
    }
    plots_.resize(plots.size());
    may_start_.resize(plots.size());
    may_not_resume_.resize(plots.size());
    for (size_t i = 0; i < plots.size(); ++i) {
      may_start_[i] = plots[i].may_start_track ? 1 : 0;
      may_not_resume_[i] = plots[i].may_resume_track ? 0 : 1;
      plots_[i].mean = plots[i].position_m.template head<D>();
      plots_[i].covariance = plots[i].covariance_m2.template topLeftCorner<D, D>();
    }
    Run(time_s, summary);
    return Status::Ok();
  }

  void Tracks(std::vector<TrackReport>* out, bool include_tentative) const override {
    out->clear();
    for (const Track& t : tracks_) {
      if (!t.history.confirmed && !include_tentative) continue;
      const FilterState<D>& f = t.filter;
      TrackReport r;
      r.id = t.id;
      r.status = !t.history.confirmed ? TrackStatus::kTentative
                                      : (t.history.misses > 0 ? TrackStatus::kCoasting : TrackStatus::kConfirmed);
      r.position_m.head<D>() = f.x.template head<D>();
      r.velocity_mps.head<D>() = f.x.template tail<D>();
      r.covariance.template topLeftCorner<D, D>() = f.p.template topLeftCorner<D, D>();
      r.covariance.template block<D, D>(0, 3) = f.p.template topRightCorner<D, D>();
      r.covariance.template block<D, D>(3, 0) = f.p.template bottomLeftCorner<D, D>();
      r.covariance.template block<D, D>(3, 3) = f.p.template bottomRightCorner<D, D>();
      r.hits = t.history.hits;
      r.consecutive_misses = t.history.misses;
      r.time_s = last_time_;
      r.steady_state = f.frozen;
      out->push_back(r);
    }
    // tracks_ is kept in order of initiation (deletion preserves order), so of id.
  }

  const TwsOptions& options() const override { return options_; }
  int track_count() const override { return static_cast<int>(tracks_.size()); }
  int64_t total_track_updates() const override { return total_updates_; }

 private:
  Status CheckPlotCount(size_t plots) const {
    if (plots <= static_cast<size_t>(options_.max_plots_per_scan)) return Status::Ok();
    return InvalidArgument("the scan has " + std::to_string(plots) + " plots; max_plots_per_scan is " +
                           std::to_string(options_.max_plots_per_scan));
  }

  Status CheckTime(double t) const {
    if (!std::isfinite(t)) return InvalidArgument("time_s is not finite");
    if (have_time_ && !(t > last_time_))
      return InvalidArgument("time_s is " + std::to_string(t) + ", not after the previous scan's " +
                             std::to_string(last_time_));
    return Status::Ok();
  }

  // One scan of plots_ at time t through the roles.
  void Run(double t, ScanSummary* summary) {
    ScanSummary s;
    s.plots = static_cast<int>(plots_.size());
    const double dt = have_time_ ? t - last_time_ : 0.0;
    s.track_updates = static_cast<int64_t>(tracks_.size());
    total_updates_ += s.track_updates;
    for (Track& tr : tracks_) updater_.Predict(tr.filter, dt);
    Associate(s);
    for (Track& tr : tracks_) {
      tr.history.Record(tr.measurement >= 0);
      if (tr.measurement >= 0) {
        updater_.Update(tr.filter, plots_[tr.measurement], dt);
        ++s.assigned;
      } else {
        updater_.Miss(tr.filter);
        if (coast_decay_ && dt > 0.0) Decay(tr.filter, std::exp(-dt / options_.coast_velocity_decay_s));
      }
    }
    Delete(s);
    Initiate(dt, s);
    for (const Track& tr : tracks_) (tr.history.confirmed ? s.confirmed : s.tentative) += 1;
    last_time_ = t;
    have_time_ = true;
    if (summary) *summary = s;
  }

  // A coasting track's velocity v -> a v: the state's linear map diag(I, a I) applied to the
  // mean and the covariance (P_vv a^2, P_pv a), with no noise added. It also ends the
  // steady-state gain (Miss already did).
  static void Decay(FilterState<D>& f, double a) {
    f.x.template tail<D>() *= a;
    f.p.template bottomRightCorner<D, D>() *= a * a;
    f.p.template topRightCorner<D, D>() *= a;
    f.p.template bottomLeftCorner<D, D>() *= a;
  }

  // Which association stage a track joins: confirmed ones that heard a plot lately (0),
  // confirmed ones silent for resume_misses scans (1: only plots that may resume a track),
  // tentative ones (2), each on the plots the stages before left.
  int StageOf(const Track& tr) const {
    if (!tr.history.confirmed) return 2;
    return options_.resume_misses > 0 && tr.history.misses >= options_.resume_misses ? 1 : 0;
  }

  void Associate(ScanSummary& s) {
    associator_.BeginScan(plots_);
    AssociationStats stats;
    for (Track& tr : tracks_) tr.measurement = -1;
    const bool filtered = options_.resume_misses > 0;
    for (int stage = 0; stage < 3; ++stage) {
      stage_tracks_.clear();
      expected_.clear();
      for (int i = 0; i < static_cast<int>(tracks_.size()); ++i) {
        if (StageOf(tracks_[i]) != stage) continue;
        stage_tracks_.push_back(i);
        expected_.push_back(updater_.Expected(tracks_[i].filter));
      }
      if (stage_tracks_.empty()) continue;
      associator_.Withhold(stage == 1 && filtered ? &may_not_resume_ : nullptr);
      associator_.Associate(expected_, &assigned_, &stats);
      associator_.Withhold(nullptr);
      for (size_t k = 0; k < stage_tracks_.size(); ++k) {
        if (assigned_[k] >= 0) tracks_[stage_tracks_[k]].measurement = assigned_[k];
      }
    }
    s.clusters = stats.clusters;
    s.largest_cluster = stats.largest_cluster;
    s.truncated_gates = stats.truncated_gates;
    s.greedy_clusters = stats.greedy_clusters;
  }

  void Delete(ScanSummary& s) {
    size_t kept = 0;
    for (size_t i = 0; i < tracks_.size(); ++i) {
      Track& tr = tracks_[i];
      initiator_.Confirm(tr.history);
      if (deleter_.Judge(tr.history, updater_.LargestPositionVariance(tr.filter)) != Deletion::kKeep) {
        ++s.deleted;
        continue;
      }
      if (kept != i) tracks_[kept] = tr;
      ++kept;
    }
    tracks_.resize(kept);
  }

  void Initiate(double dt, ScanSummary& s) {
    const int room =
        std::min(options_.max_initiations_per_scan, options_.max_tracks - static_cast<int>(tracks_.size()));
    const std::vector<char>& taken = associator_.taken();
    blocked_.resize(taken.size());
    for (size_t j = 0; j < taken.size(); ++j) blocked_[j] = taken[j] || !may_start_[j];
    initiator_.Initiate(plots_, blocked_, dt, room, &started_);
    for (const auto& st : started_) {
      Track tr;
      tr.id = next_id_++;
      tr.filter = updater_.Start(st.x, st.p);
      tr.history = st.history;
      tracks_.push_back(tr);
    }
    s.initiated = static_cast<int>(started_.size());
  }

  const TwsOptions options_;
  const bool coast_decay_ = options_.coast_velocity_decay_s > 0.0;
  const KalmanUpdater<D> updater_;
  GnnAssociator<D> associator_;
  Initiator<D> initiator_;
  const Deleter deleter_;
  std::vector<Track> tracks_;  // in order of initiation
  uint64_t next_id_ = 1;
  double last_time_ = 0.0;
  bool have_time_ = false;
  int64_t total_updates_ = 0;
  // Per-scan work arrays, kept between scans.
  std::vector<Gaussian<D>> plots_;     // the scan's plots, converted
  std::vector<char> may_start_;        // per plot: may it start a track
  std::vector<char> may_not_resume_;   // per plot: 1 if it may not update a long-silent track
  std::vector<char> blocked_;          // per plot: taken by a track, or may not start one
  std::vector<int> stage_tracks_;      // the tracks of one association stage
  std::vector<Gaussian<D>> expected_;  // and what each expects to measure
  std::vector<int> assigned_;
  std::vector<typename Initiator<D>::Started> started_;
};

}  // namespace

StatusOr<std::unique_ptr<TwsTracker>> TwsTracker::Create(const TwsOptions& options) {
  LOCALIZER_RETURN_IF_ERROR(options.Validate());
  if (options.dimensions == 2) return std::unique_ptr<TwsTracker>(new TrackerImpl<2>(options));
  return std::unique_ptr<TwsTracker>(new TrackerImpl<3>(options));
}

}  // namespace localizer::engine::tws
