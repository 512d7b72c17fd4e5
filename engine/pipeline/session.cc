#include "engine/pipeline/session.h"

#include <chrono>
#include <cmath>
#include <string>

#include "engine/array/multilateration.h"
#include "engine/filters/divergence_monitor.h"
#include "engine/pipeline/backend.h"
#include "engine/pipeline/framer.h"
#include "engine/pipeline/platform_pose.h"

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
  Impl(SessionConfig c, ArrayGeometry a, SessionComponents parts, std::unique_ptr<PlatformPose> pose)
      : config(std::move(c)),
        body_array(a),
        array(std::move(a)),
        platform(std::move(pose)),
        components(std::move(parts)),
        framer(array.sensor_count(), config.frame_samples, config.hop_samples),
        monitor(config.divergence_window) {}

  void ProcessFrame(const float* frame, int64_t first_sample, uint64_t sequence, std::vector<Estimate>* out);
  // Multilaterates this frame; true (and *fix set) when the fix is good enough to (re)start.
  bool GoodFix(const Vec3* hint, Fix* fix) const;
  // A Gaussian belief at the fix, at rest with init_speed_sigma_mps of velocity spread.
  TrackState BeliefFromFix(const Fix& fix) const;
  // Conditions the tracker on this frame, fills e's filter fields, and restarts the tracker
  // from this frame's fix when the divergence test fires.
  void UpdateAndWatch(Estimate* e);
  // The TDOA noise std for fixes: configured, else the tracker's latest adaptive estimate,
  // else 0.1 sample.
  double tdoa_sigma_s() const {
    if (config.filter.tdoa_sigma_s > 0.0) return config.filter.tdoa_sigma_s;
    return last_sigma_s > 0.0 ? last_sigma_s : 0.1 / config.sample_rate_hz;
  }

  // Moving arrays: moves `array` and the tracker to the platform's pose at t_s; false
  // when there is no pose yet (no IMU sample).
  bool MoveArray(double t_s, Estimate* e);

  SessionConfig config;
  ArrayGeometry body_array;  // as configured (the body frame, for a moving array)
  ArrayGeometry array;       // in the world at the current frame
  std::unique_ptr<PlatformPose> platform;  // moving arrays only
  SessionComponents components;
  Framer framer;
  DivergenceMonitor monitor;
  Measurement measurement;
  Eigen::VectorXd delays;
  bool have_sequence = false;
  uint64_t last_sequence = 0;
  uint64_t frames = 0;
  double last_t_s = 0.0;
  double last_sigma_s = 0.0;
};

bool Session::Impl::GoodFix(const Vec3* hint, Fix* fix) const {
  for (const PairMeasurement& p : measurement.pairs) {
    if (p.quality < config.min_pair_quality || p.peak_snr < config.filter.min_peak_snr) return false;
  }
  MultilaterationOptions options;
  options.tdoa_sigma_s = tdoa_sigma_s();
  options.hint_m = hint;
  auto result = Multilaterate(array, delays, options);
  if (!result.ok() || !result->converged) return false;
  const double max_std_m = config.max_fix_std_m > 0.0 ? config.max_fix_std_m : 5.0 * array.aperture_m();
  if (!(result->position_std_m() <= max_std_m)) return false;
  *fix = *result;
  return true;
}

TrackState Session::Impl::BeliefFromFix(const Fix& fix) const {
  TrackState belief;
  belief.mean.head<3>() = fix.position_m;
  belief.covariance.topLeftCorner<3, 3>() = fix.covariance_m2;
  belief.covariance.bottomRightCorner<3, 3>() =
      config.init_speed_sigma_mps * config.init_speed_sigma_mps * Mat3::Identity();
  return belief;
}

void Session::Impl::UpdateAndWatch(Estimate* e) {
  Tracker& tracker = *components.tracker;
  auto report = tracker.Update(measurement);
  if (!report.ok()) return;
  e->nis = report->nis;
  e->ess = report->ess;
  e->tdoa_sigma_s = report->tdoa_sigma_s;
  e->pairs_used = report->pair_count;
  last_sigma_s = report->tdoa_sigma_s;
  if (report->pair_count == 0 || !monitor.Add(report->nis, report->pair_count)) return;
  // Diverged: restart from this frame's fix (velocity reset too), if it is good enough.
  const Vec3 hint = tracker.State().mean.head<3>();
  Fix fix;
  if (GoodFix(&hint, &fix)) e->reinitialised = tracker.Initialise(BeliefFromFix(fix)).ok();
}

bool Session::Impl::MoveArray(double t_s, Estimate* e) {
  auto pose = platform->At(t_s);
  if (!pose) return false;
  array = body_array.Moved(pose->body_to_world.toRotationMatrix(), pose->origin_m);
  if (!components.tracker->SetArray(array).ok()) return false;  // a rigid motion: cannot fail
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
  bool update = measured && posed;
  if (!posed) {
    // Nothing to do until the platform's pose is known.
  } else if (tracker.initialised()) {
    tracker.Predict(e.t_s - last_t_s);
  } else if (config.init_region_min_m.allFinite()) {
    // The region is the belief at this frame; this frame's TDOAs then refine it.
    (void)tracker.InitialiseRegion(config.init_region_min_m, config.init_region_max_m,
                                   config.init_speed_sigma_mps);
    monitor.Reset();
  } else {
    Fix fix;
    if (measured && GoodFix(nullptr, &fix)) {
      (void)tracker.Initialise(BeliefFromFix(fix));
      monitor.Reset();
    }
    update = false;  // the fix already holds this frame's TDOAs
  }
  if (update && tracker.initialised()) UpdateAndWatch(&e);
  if (tracker.initialised()) {
    const TrackState state = tracker.State();
    e.initialised = true;
    e.state = state.mean;
    e.covariance = state.covariance;
    e.model_probabilities = tracker.ModelProbabilities();
  }
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
  auto parts = BuildComponents(config.backend, *array, gcc, tracker);
  if (!parts.ok()) return parts.status();
  return std::unique_ptr<Session>(new Session(
      std::make_unique<Impl>(config, std::move(array).value(), std::move(parts).value(), std::move(pose))));
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
