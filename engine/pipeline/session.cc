#include "engine/pipeline/session.h"

#include <chrono>
#include <cmath>
#include <string>

#include "engine/acquisition/acquisition.h"
#include "engine/filters/divergence_monitor.h"
#include "engine/pipeline/backend.h"
#include "engine/pipeline/framer.h"
#include "engine/pipeline/platform_pose.h"
#include "engine/tdoa/despike.h"

namespace localizer::engine {
namespace {

double SecondsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

Status ValidateBlock(const BlockView& block, int channels, int64_t max_samples, bool have_last,
                     uint64_t last_sequence) {
  if (have_last && block.sequence <= last_sequence) {
    return InvalidArgument("sequence " + std::to_string(block.sequence) +
                           " is not greater than the previous block's " + std::to_string(last_sequence));
  }
  if (block.channel_count != channels) {
    return InvalidArgument("channel_count is " + std::to_string(block.channel_count) + "; the array has " +
                           std::to_string(channels) + " sensors");
  }
  if (block.samples_per_channel < 1 || block.samples_per_channel > max_samples) {
    return InvalidArgument("samples per channel is " + std::to_string(block.samples_per_channel) +
                           "; must be in [1, " + std::to_string(max_samples) + "]");
  }
  if (block.samples == nullptr) return InvalidArgument("samples is null");
  const int64_t total = block.samples_per_channel * channels;
  bool finite = true;
  for (int64_t i = 0; i < total; ++i) finite &= std::isfinite(block.samples[i]);
  if (!finite) {
    for (int64_t i = 0; i < total; ++i) {
      if (!std::isfinite(block.samples[i])) {
        return InvalidArgument("samples[" + std::to_string(i) + "] (channel " +
                               std::to_string(i / block.samples_per_channel) + ", sample " +
                               std::to_string(i % block.samples_per_channel) + ") is not finite");
      }
    }
  }
  return Status::Ok();
}

}  // namespace

struct Session::Impl {
  Impl(SessionConfig c, ArrayGeometry a, SessionComponents parts, std::unique_ptr<PlatformPose> pose, Acquisition acq)
      : config(std::move(c)),
        body_array(a),
        array(std::move(a)),
        platform(std::move(pose)),
        components(std::move(parts)),
        acquisition(std::move(acq)),
        framer(array.sensor_count(), config.frame_samples, config.hop_samples),
        monitor(config.divergence_window) {
    despike.despike_k = config.despike_k;
    // A coherent impulse reaches every sensor within the aperture's travel time.
    despike.coincidence_samples =
        static_cast<int>(std::ceil(array.aperture_m() / config.sound_speed_mps * config.sample_rate_hz)) + 5;
  }

  void ProcessFrame(const float* frame, int64_t first_sample, uint64_t sequence, std::vector<Estimate>* out);
  // Starts the tracker from acquisition's modes (every one the data allows); false if none.
  bool StartFromModes(const std::vector<PositionMode>& modes);
  // The track's frame: predict, test presence near it, update or coast, watch for
  // divergence and for a source heard elsewhere; drops the track after source_timeout_s of
  // silence. Fills e's presence and filter fields.
  void TrackFrame(double dt_s, bool measured, Estimate* e);
  // No track: search the volume; a present source starts one.
  void AcquireFrame(bool measured, Estimate* e);
  // A present frame that the track explains much worse than each pair's best peak allows
  // (PresenceResult::unconstrained), or whose update used fewer than 3 pairs, is audited by
  // a volume search (at most every
  // kAuditSpacingFrames): no mode near the track scoring within the margin of the best, in
  // kOutscoredAudits audits in a row, restarts the track from the modes and the track
  // itself. Catches a track that locked on a wrong position while every test near it passes.
  void Audit(const TrackState& predicted, const PresenceResult& near, Estimate* e);
  // Conditions the tracker on this frame, fills e's filter fields, and restarts the tracker
  // through acquisition when the divergence test fires.
  void UpdateAndWatch(Estimate* e);
  // The estimate's state: the strongest hypothesis, with a covariance that covers all of them.
  void Report(Estimate* e) const;
  // Multipath: a pair whose main peak is far from where the track predicts it, while its GCC
  // has another peak (a local maximum at least kCandidateShare of the main peak's height)
  // within kAssociationGate predicted sigmas, is measured at that peak instead (the tallest
  // in the gate; returns how many pairs were changed).
  int AssociateCandidates(const TrackState& predicted);

  // Moving arrays: moves `array` and the tracker to the platform's pose at t_s; false
  // when there is no pose yet (no IMU sample).
  bool MoveArray(double t_s, Estimate* e);

  SessionConfig config;
  ArrayGeometry body_array;  // as configured (the body frame, for a moving array)
  ArrayGeometry array;       // in the world at the current frame
  std::unique_ptr<PlatformPose> platform;  // moving arrays only
  SessionComponents components;
  Acquisition acquisition;
  bool live = false;         // the tracker holds a track (not dropped)
  int frames_since_audit = 0;  // see Audit
  int outscored = 0;           // audits in a row that found the frame better explained elsewhere
  double silent_s = 0.0;     // time since the source was last heard near the track
  int heard_elsewhere = 0;   // consecutive frames with the source present away from the track
  Framer framer;
  DespikeOptions despike;
  DespikeScratch despike_scratch;
  std::vector<float> despiked;  // the frame as the estimator sees it, when despiking
  DivergenceMonitor monitor;
  Measurement measurement;
  Eigen::VectorXd delays;
  bool have_sequence = false;
  uint64_t last_sequence = 0;
  uint64_t frames = 0;
  double last_t_s = 0.0;
};

// Frames in a row that hear the source away from the track before it is re-acquired.
constexpr int kHeardElsewhereFrames = 3;
constexpr double kAssociationGate = 3.0;
constexpr double kAuditMargin = 3.0;  // x sqrt(P): the acquisition's mode margin
constexpr int kAuditSpacingFrames = 8;
constexpr int kOutscoredAudits = 2;

void Session::Impl::Audit(const TrackState& predicted, const PresenceResult& near, Estimate* e) {
  ++frames_since_audit;
  const double pairs = std::max(1, acquisition.field().usable_pairs());
  // Both statistics are sums over pairs / sqrt(P), so a gap of kAuditMargin here is the
  // acquisition's mode margin (kAuditMargin sqrt(P) in summed units).
  // Fewer than 3 pairs in the update leave the position unobservable: the track may drift
  // along the unobserved directions while every test near it passes.
  const bool suspicious = near.unconstrained - near.statistic > kAuditMargin || e->pairs_used < 3;
  if (!suspicious || frames_since_audit < kAuditSpacingFrames) return;
  frames_since_audit = 0;
  const AcquisitionResult found = acquisition.Search(measurement);
  if (!found.presence.present || found.modes.empty()) return;
  const Mat3 track_cov = predicted.covariance.topLeftCorner<3, 3>();
  const double best = found.modes.front().score;
  for (const PositionMode& mode : found.modes) {
    const Vec3 delta = mode.position_m - predicted.mean.head<3>();
    const bool near_track = delta.dot((track_cov + mode.covariance_m2).ldlt().solve(delta)) < 16.0;
    if (near_track && mode.score >= best - kAuditMargin * std::sqrt(pairs)) {
      outscored = 0;
      return;
    }
  }
  if (++outscored < kOutscoredAudits) return;
  outscored = 0;
  // Restart from every mode and the track's own position: the data decide.
  std::vector<PositionMode> modes = found.modes;
  PositionMode own;
  own.position_m = predicted.mean.head<3>();
  own.covariance_m2 = track_cov;
  modes.push_back(own);
  e->reinitialised = StartFromModes(modes);
}
constexpr double kCandidateShare = 0.3;

int Session::Impl::AssociateCandidates(const TrackState& predicted) {
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
    pair.delay_s = (pair.first_lag_samples + best + offset) / fs;
    pair.delay_sigma_s = 0.0;  // the anchor then comes from this peak's own curvature
    pair.confirmed = true;
    ++changed;
  }
  return changed;
}

bool Session::Impl::StartFromModes(const std::vector<PositionMode>& modes) {
  if (modes.empty()) return false;
  std::vector<WeightedBelief> mixture;
  for (const PositionMode& mode : modes) {
    WeightedBelief b;
    b.weight = 1.0;  // equal: the measurements and the dynamics decide between them
    b.belief.mean.head<3>() = mode.position_m;
    b.belief.covariance.topLeftCorner<3, 3>() = mode.covariance_m2;
    b.belief.covariance.bottomRightCorner<3, 3>() =
        config.init_speed_sigma_mps * config.init_speed_sigma_mps * Mat3::Identity();
    mixture.push_back(b);
  }
  if (!components.tracker->InitialiseMixture(mixture).ok()) return false;
  live = true;
  silent_s = 0.0;
  heard_elsewhere = 0;
  outscored = 0;
  frames_since_audit = 0;
  monitor.Reset();
  return true;
}

void Session::Impl::UpdateAndWatch(Estimate* e) {
  Tracker& tracker = *components.tracker;
  auto report = tracker.Update(measurement);
  if (!report.ok()) return;
  e->nis = report->nis;
  e->ess = report->ess;
  e->tdoa_sigma_s = report->tdoa_sigma_s;
  e->pairs_used = report->pair_count;
  if (report->pair_count == 0 || !monitor.Add(report->anchored_nis, report->pair_count, report->anchored_z)) return;
  // Diverged: every hypothesis this frame allows, through acquisition (velocity reset too).
  const AcquisitionResult found = acquisition.Search(measurement);
  if (found.presence.present) e->reinitialised = StartFromModes(found.modes);
}

void Session::Impl::TrackFrame(double dt_s, bool measured, Estimate* e) {
  Tracker& tracker = *components.tracker;
  tracker.Predict(dt_s);
  if (!measured) return;
  const TrackState predicted = tracker.Hypotheses().front().belief;
  const PresenceResult near = acquisition.Around(measurement, predicted.mean.head<3>(),
                                                 predicted.covariance.topLeftCorner<3, 3>());
  e->presence_statistic = near.statistic;
  e->presence_threshold = near.threshold;
  if (near.present) {
    e->source_present = true;
    silent_s = 0.0;
    heard_elsewhere = 0;
    AssociateCandidates(predicted);
    UpdateAndWatch(e);
    if (!e->reinitialised) Audit(predicted, near, e);
    return;
  }
  // Not near the track: silence, or a source the track has lost?
  const AcquisitionResult found = acquisition.Search(measurement);
  if (found.presence.present) {
    e->source_present = true;
    e->presence_statistic = found.presence.statistic;
    e->presence_threshold = found.presence.threshold;
    silent_s = 0.0;
    // A mode within the track's own uncertainty is the track's source, heard on a frame
    // whose peaks the local test missed: update as usual.
    const Mat3 track_cov = predicted.covariance.topLeftCorner<3, 3>();
    for (const PositionMode& mode : found.modes) {
      const Vec3 delta = mode.position_m - predicted.mean.head<3>();
      if (delta.dot((track_cov + mode.covariance_m2).ldlt().solve(delta)) < 16.0) {
        heard_elsewhere = 0;
        AssociateCandidates(predicted);
        UpdateAndWatch(e);
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

void Session::Impl::AcquireFrame(bool measured, Estimate* e) {
  if (!measured) return;
  const AcquisitionResult found = acquisition.Search(measurement);
  e->source_present = found.presence.present;
  e->presence_statistic = found.presence.statistic;
  e->presence_threshold = found.presence.threshold;
  if (found.presence.present) StartFromModes(found.modes);
}

void Session::Impl::Report(Estimate* e) const {
  const std::vector<WeightedBelief> hypotheses = components.tracker->Hypotheses();
  const TrackState& best = hypotheses.front().belief;
  Mat6 covariance = Mat6::Zero();
  int modes = 0;
  for (const WeightedBelief& h : hypotheses) {
    const Vec6 offset = h.belief.mean - best.mean;
    covariance += h.weight * (h.belief.covariance + offset * offset.transpose());
    modes += h.weight >= 0.01;
  }
  e->initialised = true;
  e->state = best.mean;
  // Positions outside the bounds are impossible (the particle filter keeps its particles in;
  // the Kalman filters' Gaussian may straddle a wall).
  e->state.head<3>() = e->state.head<3>().cwiseMax(config.bounds_min_m).cwiseMin(config.bounds_max_m);
  e->covariance = covariance;
  e->modes = std::max(modes, 1);
  e->ambiguous = e->modes > 1;
  e->model_probabilities = components.tracker->ModelProbabilities();
}

bool Session::Impl::MoveArray(double t_s, Estimate* e) {
  auto pose = platform->At(t_s);
  if (!pose) return false;
  array = body_array.Moved(pose->body_to_world.toRotationMatrix(), pose->origin_m);
  if (!components.tracker->SetArray(array).ok()) return false;  // a rigid motion: cannot fail
  acquisition.SetArray(array);
  e->platform = *pose;
  return true;
}

void Session::Impl::ProcessFrame(const float* frame, int64_t first_sample, uint64_t sequence,
                                 std::vector<Estimate>* out) {
  Estimate e;
  e.frame_index = frames++;
  e.sequence = sequence;
  e.t_s = (static_cast<double>(first_sample) + 0.5 * (config.frame_samples - 1)) / config.sample_rate_hz;

  const auto tdoa_start = std::chrono::steady_clock::now();
  if (despike.despike_k > 0.0) {
    despiked.assign(frame, frame + static_cast<size_t>(array.sensor_count()) * config.frame_samples);
    (void)Despike(despike, despiked.data(), array.sensor_count(), config.frame_samples, &despike_scratch);
    frame = despiked.data();
  }
  const bool measured = components.estimator->Estimate(frame, config.frame_samples, e.t_s, &measurement).ok();
  e.timings.tdoa_s = SecondsSince(tdoa_start);

  const auto filter_start = std::chrono::steady_clock::now();
  // A moving array without a pose yet: the frame is measured but cannot be tracked.
  const bool posed = platform == nullptr || MoveArray(e.t_s, &e);
  if (measured) {
    delays.resize(static_cast<Eigen::Index>(measurement.pairs.size()));
    for (size_t p = 0; p < measurement.pairs.size(); ++p) {
      delays(static_cast<Eigen::Index>(p)) = measurement.pairs[p].delay_s;
      e.delay_s.push_back(measurement.pairs[p].delay_s);
      e.quality.push_back(measurement.pairs[p].quality);
    }
  }
  Tracker& tracker = *components.tracker;
  if (!posed) {
    // Nothing to do until the platform's pose is known.
  } else if (live && tracker.initialised()) {
    TrackFrame(e.t_s - last_t_s, measured, &e);
  } else if (config.init_region_min_m.allFinite()) {
    // The region is the belief at this frame; this frame's TDOAs then refine it.
    live = tracker.InitialiseRegion(config.init_region_min_m, config.init_region_max_m,
                                    config.init_speed_sigma_mps).ok();
    monitor.Reset();
    if (live && measured) {
      e.source_present = true;  // the user says so; the presence test runs once tracking
      UpdateAndWatch(&e);
    }
  } else {
    AcquireFrame(measured, &e);  // the modes already hold this frame's TDOAs
  }
  if (live && tracker.initialised()) Report(&e);
  last_t_s = e.t_s;
  e.timings.filter_s = SecondsSince(filter_start);
  out->push_back(std::move(e));
}

Session::Session(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
Session::~Session() = default;

StatusOr<std::unique_ptr<Session>> Session::Create(const SessionConfig& config) {
  if (config.detections) return InvalidArgument("a detections config makes a ScanSession (scan_session.h), not a Session");
  LOCALIZER_RETURN_IF_ERROR(config.Validate());
  auto array = ArrayGeometry::Create(config.sensors_m, config.sound_speed_mps, config.reference_sensor);
  if (!array.ok()) return array.status();
  const GccOptions gcc = config.GccOptionsFor();
  TrackerOptions tracker;
  tracker.type = config.filter_type;
  tracker.particle = config.filter;
  tracker.particle.seed = config.seed;
  tracker.kalman.motion_model = config.motion_model;
  tracker.kalman.motion.accel_noise_mps2 = config.filter.accel_noise_mps2;
  tracker.kalman.tdoa_sigma_s = config.filter.tdoa_sigma_s;
  tracker.kalman.min_peak_snr = config.filter.min_peak_snr;
  tracker.kalman.robust = *ParseRobustUpdate(config.robust);  // validated above
  if (config.filter_type == "imm") {
    tracker.kalman.variant = config.imm_variant == "ukf" ? KalmanVariant::kUnscented : KalmanVariant::kExtended;
    tracker.imm_modes = *ParseImmModes(config.imm_modes, tracker.kalman.motion);
  }
  tracker.moving_array = config.array_in_body_frame;
  std::unique_ptr<PlatformPose> pose;
  if (config.array_in_body_frame) {
    auto made = PlatformPose::Create(config.attitude, config.platform_origin_m);
    if (!made.ok()) return made.status();
    pose = std::move(made).value();
  }
  AcquisitionOptions search;
  search.bounds_min_m = config.bounds_min_m;
  search.bounds_max_m = config.bounds_max_m;
  search.search_radius_m = config.search_radius_m;
  search.false_alarm = config.presence_false_alarm;
  auto acquisition = Acquisition::Create(*array, search);
  if (!acquisition.ok()) return acquisition.status();
  auto parts = BuildComponents(config.backend, *array, gcc, tracker);
  if (!parts.ok()) return parts.status();
  parts->tracker->SetBounds(config.bounds_min_m, config.bounds_max_m);
  return std::unique_ptr<Session>(new Session(std::make_unique<Impl>(
      config, std::move(array).value(), std::move(parts).value(), std::move(pose), std::move(acquisition).value())));
}

Status Session::Process(const BlockView& block, std::vector<Estimate>* out) {
  Impl& s = *impl_;
  LOCALIZER_RETURN_IF_ERROR(ValidateBlock(block, s.array.sensor_count(), s.config.max_block_samples,
                                          s.have_sequence, s.last_sequence));
  s.have_sequence = true;
  s.last_sequence = block.sequence;
  s.framer.Append(block);
  const float* frame = nullptr;
  int64_t first = 0;
  while (s.framer.Next(&frame, &first)) s.ProcessFrame(frame, first, block.sequence, out);
  return Status::Ok();
}

Status Session::Skip(int64_t samples_per_channel) {
  if (samples_per_channel < 0 || samples_per_channel > (int64_t{1} << 40)) {
    return InvalidArgument("skipped samples " + std::to_string(samples_per_channel) + " not in [0, 2^40]");
  }
  impl_->framer.Skip(samples_per_channel);
  return Status::Ok();
}

Status Session::AddImu(const std::vector<ImuSample>& samples) {
  if (impl_->platform == nullptr) {
    return FailedPrecondition("IMU samples for a session whose array is fixed in the world "
                              "(open it with the array in the platform's body frame)");
  }
  return impl_->platform->Add(samples);
}

Status Session::SetPlatformOrigin(const Vec3& origin_m) {
  if (impl_->platform == nullptr) {
    return FailedPrecondition("platform origin for a session whose array is fixed in the world");
  }
  return impl_->platform->SetOrigin(origin_m);
}

const SessionConfig& Session::config() const { return impl_->config; }
const std::string& Session::backend() const { return impl_->components.backend; }
const ArrayGeometry& Session::array() const { return impl_->array; }
uint64_t Session::frames_processed() const { return impl_->frames; }

}  // namespace localizer::engine
