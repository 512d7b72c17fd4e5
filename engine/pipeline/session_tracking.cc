// Session::Impl's tracking steps (session_impl.h): acquisition, presence about the track,
// multipath association, audits, the update with its divergence watch, and the estimate's
// hypotheses. See session.h for the behaviour these implement.
#include <algorithm>
#include <cmath>
#include <vector>

#include "engine/core/covariance_repair.h"
#include "engine/filters/pair_noise.h"
#include "engine/pipeline/session_impl.h"

namespace localizer::engine {

// Frames in a row that hear the source away from the track before it is re-acquired.
constexpr int kHeardElsewhereFrames = 3;
constexpr double kAssociationGate = 3.0;
constexpr double kAuditMargin = 3.0;  // x sqrt(P): the acquisition's mode margin
constexpr int kAuditSpacingFrames = 8;
constexpr int kOutscoredAudits = 2;
// Reported frames an audit's outscoring mode stays in the estimate's covariance without an
// audit judging again: two audits' spacing.
constexpr int kContenderFrames = 2 * kAuditSpacingFrames;
// A live mirror's weight in the reported covariance (mirror_watch.h): the heaviest mode's own
// is 1, so a mirror at d from the track is covered at about d / sqrt(kMirrorWeight) sds, as a
// contender of the particle filter is (particle_set.h, kContenderShare).
constexpr double kMirrorWeight = 0.1;
// Delay rates are handed to the front end when some pair's peak would move by this many
// samples over a frame (a slower track's frames are read as they are, bit for bit). Rates the
// front end refuses (GccPhatEstimator's bound) leave the frame read as it is.
constexpr double kMinMigrationSamples = 1.0;

// The mode lies within the track's and its own uncertainty (Mahalanobis distance < 4).
bool NearTrack(const TrackState& predicted, const PositionMode& mode) {
  const Vec3 delta = mode.position_m - predicted.mean.head<3>();
  const Mat3 spread = predicted.covariance.topLeftCorner<3, 3>() + mode.covariance_m2;
  return delta.dot(spread.ldlt().solve(delta)) < 16.0;
}

// The modes plus the track's own predicted position as one more (equal weight).
std::vector<PositionMode> WithOwnTrack(std::vector<PositionMode> modes, const TrackState& predicted) {
  PositionMode own;
  own.position_m = predicted.mean.head<3>();
  own.covariance_m2 = predicted.covariance.topLeftCorner<3, 3>();
  modes.push_back(own);
  return modes;
}

void Session::Impl::Audit(const TrackState& predicted, const PresenceResult& near, Estimate* e) {
  ++frames_since_audit;
  if (frames_since_audit < kAuditSpacingFrames) return;
  const double pairs = std::max(1, acquisition.field().usable_pairs());
  // Both statistics are sums over pairs / sqrt(P), so a gap of kAuditMargin here is the
  // acquisition's mode margin (kAuditMargin sqrt(P) in summed units).
  // Fewer than 3 pairs in the update leave the position unobservable: the track may drift
  // along the unobserved directions while every test near it passes.
  const bool suspicious = near.unconstrained - near.statistic > kAuditMargin || e->pairs_used < 3 ||
                          (frames_since_audit % kAuditSpacingFrames == 0 && EchoedChannelAtTrack(predicted));
  if (!suspicious) return;
  frames_since_audit = 0;
  const AcquisitionResult found = SearchAllPairs();
  if (!found.presence.present || found.modes.empty()) return;
  const double best = found.modes.front().score;
  // One side of a channel's echo and its earlier arrival, away from the track.
  const auto other_side = [&]() -> std::optional<PositionMode> {
    for (const PositionMode& mode : found.modes) {
      if (mode.earlier_arrival && !NearTrack(predicted, mode)) return mode;
    }
    return std::nullopt;
  };
  for (const PositionMode& mode : found.modes) {
    if (NearTrack(predicted, mode) && (mode.score >= best - kAuditMargin * std::sqrt(pairs) || mode.earlier_arrival)) {
      outscored = 0;
      // On the earlier arrival, the echo that outscores it is the other side; on a mode
      // within the margin, a lone channel's earlier arrival elsewhere is.
      contender =
          mode.earlier_arrival && !NearTrack(predicted, found.modes.front()) ? found.modes.front() : other_side();
      contender_frames = 0;
      return;
    }
  }
  // Until the next audit judges again (or a restart), the estimate covers the mode that
  // outscored the track: a track the data no longer favour is not reported as sure.
  contender = found.modes.front();
  contender_frames = 0;
  if (++outscored < kOutscoredAudits) return;
  outscored = 0;
  // Restart from every mode and the track's own position: the data decide.
  e->reinitialised = StartFromModes(WithOwnTrack(found.modes, predicted));
}

bool Session::Impl::EchoedChannelAtTrack(const TrackState& predicted) {
  if (array.sensor_count() > config.cross_pairs_max_sensors) return false;
  MeasureCrossPairsOnce();
  if (measurement.cross_pairs.empty()) return false;
  (void)acquisition.Around(measurement, predicted.mean.head<3>(), predicted.covariance.topLeftCorner<3, 3>());
  std::vector<double> lags;
  return acquisition.EarlierArrival(predicted.mean.head<3>(), &lags);
}

constexpr double kCandidateShare = 0.3;

int Session::Impl::AssociateCandidates(const TrackState& predicted, size_t hypotheses) {
  // `predicted` is the heaviest hypothesis: peaks picked near it would be the others'
  // measurements too, and would hand it the frame (campaign scene 2000127).
  if (hypotheses > 1) return 0;
  const Vec3 position = predicted.mean.head<3>();
  const double fs = config.sample_rate_hz;
  const Eigen::VectorXd lag = array.Tdoa(position) * fs;
  const Eigen::MatrixXd jac = array.TdoaJacobian(position) * fs;
  const Mat3 cov = predicted.covariance.topLeftCorner<3, 3>();
  int changed = 0;
  for (size_t p = 0; p < measurement.pairs.size(); ++p) {
    PairMeasurement& pair = measurement.pairs[p];
    const std::vector<float>& g = pair.gcc;
    if (g.size() < 3 || !(pair.peak_value > 0.0)) continue;
    const Eigen::Vector3d row = jac.row(static_cast<Eigen::Index>(p)).transpose();
    const double sigma = std::max(pair.delay_sigma_s * fs, 0.05);
    const double gate = kAssociationGate * std::sqrt(row.dot(cov * row) + sigma * sigma);  // samples
    const double predicted_lag = lag(static_cast<Eigen::Index>(p));
    if (std::abs(pair.delay_s * fs - predicted_lag) <= gate) {
      pair.confirmed = true;
      continue;
    }
    // The largest local maximum of the pair's GCC inside the gate, if tall enough.
    const long lo = std::max(1L, static_cast<long>(std::ceil(predicted_lag - gate)) - pair.first_lag_samples);
    const long hi = std::min(static_cast<long>(g.size()) - 2,
                             static_cast<long>(std::floor(predicted_lag + gate)) - pair.first_lag_samples);
    long best = -1;
    for (long i = lo; i <= hi; ++i) {
      const size_t k = static_cast<size_t>(i);
      if (g[k] > g[k - 1] && g[k] >= g[k + 1] && (best < 0 || g[k] > g[static_cast<size_t>(best)])) best = i;
    }
    if (best < 0 || g[static_cast<size_t>(best)] < kCandidateShare * pair.peak_value) continue;
    const size_t k = static_cast<size_t>(best);
    const double a = g[k - 1], b = g[k], c = g[k + 1], denom = a - 2.0 * b + c;
    const double offset = denom < 0.0 ? std::clamp(0.5 * (a - c) / denom, -0.5, 0.5) : 0.0;
    pair.delay_s = (static_cast<double>(pair.first_lag_samples + best) + offset) / fs;
    // The pair's tallest peak says it hears the source (the filters' peak SNR floor); this
    // peak's precision is its own: its curvature at its own height (0: the filters fall
    // back on the tallest's SNR).
    pair.delay_sigma_s = OwnPeakSigmaS(pair, fs);
    pair.confirmed = true;
    ++changed;
  }
  return changed;
}

bool Session::Impl::StartFromModes(const std::vector<PositionMode>& modes) {
  if (modes.empty()) return false;
  std::vector<WeightedBelief> mixture;
  auto add = [&](double weight, const Vec3& position_m, const Mat3& covariance_m2) {
    WeightedBelief b;
    b.weight = weight;
    b.belief.mean.head<3>() = position_m;
    b.belief.covariance.topLeftCorner<3, 3>() = covariance_m2;
    b.belief.covariance.bottomRightCorner<3, 3>() =
        config.init_speed_sigma_mps * config.init_speed_sigma_mps * Mat3::Identity();
    mixture.push_back(b);
  };
  // Equal weights: the measurements and the dynamics decide between the modes. A mode whose
  // position along a curve is open keeps its own point and adds the others along the curve,
  // which share one more weight among them. Every mode comes first: the filter keeps at most
  // ParticleSet::kMaxLabels components, and what it leaves out is then points along a curve,
  // never a mode (the track's own among them).
  std::vector<const CurvePoint*> along;
  for (const PositionMode& mode : modes) {
    add(1.0, mode.position_m, mode.covariance_m2);
    if (mode.open_curve.empty()) continue;
    const CurvePoint* own = &mode.open_curve.front();
    for (const CurvePoint& point : mode.open_curve) {
      if ((point.position_m - mode.position_m).norm() < (own->position_m - mode.position_m).norm()) own = &point;
    }
    for (const CurvePoint& point : mode.open_curve) {
      if (&point != own) along.push_back(&point);
    }
  }
  for (const CurvePoint* point : along) {
    add(1.0 / static_cast<double>(along.size()), point->position_m, point->covariance_m2);
  }
  if (!components.tracker->InitialiseMixture(mixture).ok()) return false;
  live = true;
  silent_s = 0.0;
  heard_elsewhere = 0;
  outscored = 0;
  contender.reset();
  mirror.Reset();
  measured_mirror.Reset();
  frames_since_audit = 0;
  monitor.Reset();
  consistency.Reset();
  return true;
}

void Session::Impl::UpdateAndWatch(const TrackState& predicted, Estimate* e) {
  Tracker& tracker = *components.tracker;
  auto report = tracker.Update(measurement);
  if (!report.ok()) return;
  e->nis = report->nis;
  e->ess = report->ess;
  e->tdoa_sigma_s = report->tdoa_sigma_s;
  e->pairs_used = report->pair_count;
  consistency.Add(report->nis, report->pair_count, report->nis_terms);
  if (report->pair_count == 0 || !monitor.Add(report->anchored_nis, report->pair_count, report->anchored_z)) {
    if (report->pair_count > 0) WatchMirror(e->t_s, report->tdoa_sigma_s, report->pair_count);
    return;
  }
  // Diverged: every hypothesis this frame allows, through acquisition (velocity reset too),
  // and the track's own: the frame that tripped the test may itself hold the bad pair (a
  // 4-sensor array's three pairs always have an exact, wrong, solution with one pair off).
  const AcquisitionResult found = SearchAllPairs();
  if (found.presence.present) e->reinitialised = StartFromModes(WithOwnTrack(found.modes, predicted));
}

void Session::Impl::WatchMirror(double t_s, double fallback_sigma_s, int pairs_used) {
  // With several hypotheses the watch follows the heaviest one's mirror, so that it has seen the
  // mirror move by the time one is left (Report uses it only then).
  const std::vector<WeightedBelief> hypotheses = components.tracker->Hypotheses();
  MirrorWatch::Region region;
  region.bounds_min_m = config.bounds_min_m;
  region.bounds_max_m = config.bounds_max_m;
  region.centre_m = array.centroid_m();
  region.radius_m = acquisition.search_radius_m();
  const TrackState& track = hypotheses.front().belief;
  Eigen::VectorXd measured_s;
  if (pairs_used == 3 && measurement.pairs.size() == 3) {
    measured_s.resize(3);
    for (size_t p = 0; p < 3; ++p) measured_s(static_cast<Eigen::Index>(p)) = measurement.pairs[p].delay_s;
  }
  const Eigen::VectorXd sigma_s = pair_sigmas.Median();
  mirror.Update(array, t_s, track.mean.head<3>(), track.covariance.topLeftCorner<3, 3>(), Eigen::VectorXd(), sigma_s,
                fallback_sigma_s, region);
  measured_mirror.Update(array, t_s, track.mean.head<3>(), track.covariance.topLeftCorner<3, 3>(), measured_s, sigma_s,
                         fallback_sigma_s, region);
}

void Session::Impl::TrackFrame(double dt_s, bool measured, Estimate* e) {
  Tracker& tracker = *components.tracker;
  tracker.Predict(dt_s);
  if (!measured) return;
  const std::vector<WeightedBelief> prior = tracker.Hypotheses();
  const TrackState& predicted = prior.front().belief;
  const PresenceResult near =
      acquisition.Around(measurement, predicted.mean.head<3>(), predicted.covariance.topLeftCorner<3, 3>());
  e->presence_statistic = near.statistic;
  e->presence_threshold = near.threshold;
  if (near.present) {
    e->source_present = true;
    silent_s = 0.0;
    heard_elsewhere = 0;
    AssociateCandidates(predicted, prior.size());
    CheckClosure();
    FusePairs(predicted);
    UpdateAndWatch(predicted, e);
    if (!e->reinitialised) Audit(predicted, near, e);
    return;
  }
  // Not near the track: silence, or a source the track has lost?
  const AcquisitionResult found = SearchAllPairs();
  if (found.presence.present) {
    e->source_present = true;
    e->presence_statistic = found.presence.statistic;
    e->presence_threshold = found.presence.threshold;
    silent_s = 0.0;
    // A mode within the track's own uncertainty is the track's source, heard on a frame
    // whose peaks the local test missed: update as usual.
    for (const PositionMode& mode : found.modes) {
      if (NearTrack(predicted, mode)) {
        heard_elsewhere = 0;
        AssociateCandidates(predicted, prior.size());
        CheckClosure();
        FusePairs(predicted);
        UpdateAndWatch(predicted, e);
        return;
      }
    }
    if (++heard_elsewhere >= kHeardElsewhereFrames) e->reinitialised = StartFromModes(found.modes);
    return;
  }
  heard_elsewhere = 0;
  silent_s += dt_s;
  if (silent_s >= config.source_timeout_s) live = false;  // dropped: acquisition restarts
}

void Session::Impl::CheckClosure() {
  if (!config.pair_closure || array.sensor_count() > config.cross_pairs_max_sensors) return;
  MeasureCrossPairsOnce();  // none measured: nothing is checked
  const ClosureRepair repair = closure.Repair(&measurement);
  // A pair moved onto a peak of its own states that peak's precision, not its tallest's
  // (the repair leaves the sigma to the filters, which would read it at the tallest's SNR).
  if (repair.pair >= 0 && repair.own_peak) {
    PairMeasurement& pair = measurement.pairs[static_cast<size_t>(repair.pair)];
    pair.delay_sigma_s = OwnPeakSigmaS(pair, config.sample_rate_hz);
  }
}

void Session::Impl::FusePairs(const TrackState& predicted) {
  // The GCC likelihood reads each reference pair's GCC function, not its peak: a fused delay
  // would only narrow the width it is read with.
  if (!config.pair_fusion || array.sensor_count() > config.cross_pairs_max_sensors ||
      config.tracker.particle.likelihood == Likelihood::kGcc) {
    return;
  }
  MeasureCrossPairsOnce();
  // The track's delay rates put each cross pair at its reference pairs' instants (a fixed
  // array: a moving one's rates also hold its own motion, not modelled here).
  fusion_rates.clear();
  if (platform == nullptr) {
    const Eigen::VectorXd rates = array.TdoaJacobian(predicted.mean.head<3>()) * predicted.mean.tail<3>();
    if (rates.allFinite()) fusion_rates.assign(rates.data(), rates.data() + rates.size());
  }
  (void)fusion.Fuse(&measurement, fusion_rates);
}

void Session::Impl::MeasureCrossPairsOnce() {
  // A failed request leaves them empty: the callers then use the reference pairs alone.
  if (measurement.cross_pairs.empty()) (void)components.estimator->MeasureCrossPairs(&measurement);
}

AcquisitionResult Session::Impl::SearchAllPairs() {
  MeasureCrossPairsOnce();
  return acquisition.Search(measurement);
}

void Session::Impl::AcquireFrame(bool measured, Estimate* e) {
  if (!measured) return;
  const AcquisitionResult found = SearchAllPairs();
  e->source_present = found.presence.present;
  e->presence_statistic = found.presence.statistic;
  e->presence_threshold = found.presence.threshold;
  if (found.presence.present) StartFromModes(found.modes);
}

void Session::Impl::Report(Estimate* e) {
  const std::vector<WeightedBelief> hypotheses = components.tracker->Hypotheses();
  const TrackState& best = hypotheses.front().belief;
  single_track_mean = hypotheses.size() == 1 ? std::optional<Vec6>(best.mean) : std::nullopt;
  Mat6 covariance = Mat6::Zero();
  int modes = 0;
  for (const WeightedBelief& h : hypotheses) {
    const Vec6 offset = h.belief.mean - best.mean;
    covariance += h.weight * (h.belief.covariance + offset * offset.transpose());
    modes += h.weight >= 0.01;
  }
  // A position beside the tracker's own hypotheses, covered with kMirrorWeight.
  const auto cover = [&](const Vec3& position_m, const Mat3& covariance_m2) {
    const Vec3 offset = position_m - best.mean.head<3>();
    covariance.topLeftCorner<3, 3>() += kMirrorWeight * (covariance_m2 + offset * offset.transpose());
    ++modes;
  };
  if (contender && ++contender_frames > kContenderFrames) contender.reset();
  if (contender) cover(contender->position_m, contender->covariance_m2);
  if (hypotheses.size() == 1) {
    const std::optional<MirrorWatch::Mirror> own = mirror.Live();
    const std::optional<MirrorWatch::Mirror> measured = measured_mirror.Live();
    if (own) cover(own->position_m, own->covariance_m2);
    // The measured one too where it is a position of its own: farther from the first than 4 x
    // the root of their covariances' summed trace.
    if (measured && (!own || (measured->position_m - own->position_m).norm() >
                                 4.0 * std::sqrt((own->covariance_m2 + measured->covariance_m2).trace()))) {
      cover(measured->position_m, measured->covariance_m2);
    }
  }
  e->initialised = true;
  e->state = best.mean;
  // Positions outside the bounds are impossible (the particle filter keeps its particles in;
  // the Kalman filters' Gaussian may straddle a wall).
  e->state.head<3>() = e->state.head<3>().cwiseMax(config.bounds_min_m).cwiseMin(config.bounds_max_m);
  // Innovations that disagree with the track widen what it reports (innovation_consistency.h).
  // Positive definite even where float moments left a thin direction below zero
  // (covariance_repair.h).
  e->covariance = PositiveDefinite<6>(covariance * consistency.Inflation());
  e->modes = std::max(modes, 1);
  e->ambiguous = e->modes > 1;
  const RangeObservability range = JudgeRange(array, e->state.head<3>(), pair_sigmas.Median());
  e->range_sd_m = range.range_sd_m;
  e->far_field = range.far_field;
  e->model_probabilities = components.tracker->ModelProbabilities();
}

void Session::Impl::PredictDelayRates(double t_s) {
  const bool predicted = config.delay_rate_compensation && live && components.tracker->initialised() &&
                         single_track_mean && platform == nullptr;
  if (predicted) {
    const Vec3 velocity_mps = single_track_mean->tail<3>();
    const Vec3 at_m = single_track_mean->head<3>() + (t_s - last_t_s) * velocity_mps;
    // The mean rate, not one shrunk by the velocity's uncertainty: the mean leaves the least
    // expected migration (and measured better: ACCURACY.md, twenty-third pass); a wrong one
    // loses to the plain reading in the front end.
    const Eigen::VectorXd rates = array.TdoaJacobian(at_m) * velocity_mps;
    if (rates.allFinite() && rates.cwiseAbs().maxCoeff() * config.frame_samples >= kMinMigrationSamples) {
      delay_rates.assign(rates.data(), rates.data() + rates.size());
      if (components.estimator->SetDelayRates(delay_rates).ok()) return;
    }
  }
  if (delay_rates.empty()) return;
  delay_rates.clear();
  (void)components.estimator->SetDelayRates({});
}

}  // namespace localizer::engine
