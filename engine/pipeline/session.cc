#include "engine/pipeline/session.h"

#include <chrono>
#include <cmath>
#include <string>

#include "engine/core/finite.h"
#include "engine/pipeline/direction_stage.h"
#include "engine/pipeline/session_impl.h"

namespace localizer::engine {
namespace {

double SecondsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

Status ValidateBlock(const BlockView& block, int channels, int64_t max_samples, bool have_last,
                     uint64_t last_sequence) {
  if (have_last && block.sequence <= last_sequence) {
    return InvalidArgument("sequence " + std::to_string(block.sequence) + " is not greater than the previous block's " +
                           std::to_string(last_sequence));
  }
  if (block.channel_count != channels) {
    return InvalidArgument("channel_count is " + std::to_string(block.channel_count) + "; the array has " +
                           std::to_string(channels) + " sensors");
  }
  if (block.samples_per_channel < 1 || block.samples_per_channel > max_samples) {
    return InvalidArgument("samples per channel is " + std::to_string(block.samples_per_channel) + "; must be in [1, " +
                           std::to_string(max_samples) + "]");
  }
  if (block.samples == nullptr) return InvalidArgument("samples is null");
  const int64_t total = block.samples_per_channel * channels;
  if (!AllFinite(block.samples, total)) {
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

double FrameCentre_s(int64_t first_sample, const AudioSessionConfig& config) {
  return (static_cast<double>(first_sample) + 0.5 * (config.frame_samples - 1)) / config.sample_rate_hz;
}

}  // namespace

// A direction session's state: the block intake (as Impl's) and the frame step.
struct Session::DirectionImpl {
  DirectionImpl(AudioSessionConfig c, std::unique_ptr<DirectionStage> s)
      : config(std::move(c)),
        stage(std::move(s)),
        framer(static_cast<int>(config.sensors_m.size()), config.frame_samples, config.hop_samples) {}
  AudioSessionConfig config;
  std::unique_ptr<DirectionStage> stage;
  Framer framer;
  bool have_sequence = false;
  uint64_t last_sequence = 0;
  uint64_t frames = 0;
  std::string backend = "cpu";
};

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
  e.t_s = FrameCentre_s(first_sample, config);

  const auto tdoa_start = std::chrono::steady_clock::now();
  PredictDelayRates(e.t_s);
  if (despike.despike_k > 0.0) {  // a frame with nothing to clip is read where it is
    const auto despiked_frame =
        DespikedFrame(despike, frame, array.sensor_count(), config.frame_samples, &despike_scratch, &despiked);
    if (despiked_frame.ok()) frame = *despiked_frame;
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
    live =
        tracker.InitialiseRegion(config.init_region_min_m, config.init_region_max_m, config.init_speed_sigma_mps).ok();
    monitor.Reset();
    consistency.Reset();
    if (live && measured) {
      e.source_present = true;  // the user says so; the presence test runs once tracking
      UpdateAndWatch(tracker.Hypotheses().front().belief, &e);
    }
  } else {
    AcquireFrame(measured, &e);  // the modes already hold this frame's TDOAs
  }
  if (measured) pair_sigmas.Add(measurement, e.tdoa_sigma_s);
  if (live && tracker.initialised()) Report(&e);
  last_t_s = e.t_s;
  e.timings.filter_s = SecondsSince(filter_start);
  out->push_back(std::move(e));
}

Session::Session(ArrayShapeInfo shape, Localization localization, std::unique_ptr<Impl> impl,
                 std::unique_ptr<DirectionImpl> direction)
    : shape_(shape), localization_(localization), impl_(std::move(impl)), direction_(std::move(direction)) {}
Session::~Session() = default;

namespace {

// The array's shape and what a session on it reports (ResolveLocalization).
struct Resolved {
  ArrayShapeInfo shape;
  Localization localization = Localization::kAuto;
  bool sources = false;  // the estimates list sources (Estimate::sources)
};

StatusOr<Resolved> Resolve(const AudioSessionConfig& config) {
  auto shape = ClassifyArray(config.sensors_m);
  if (!shape.ok()) return InvalidArgument("array.sensors_m: " + shape.status().message());
  const bool volumetric = shape->shape == ArrayShape::kVolumetric;
  const bool linear = shape->shape == ArrayShape::kLinear;
  Localization localization = config.localization;
  if (localization == Localization::kAuto) {
    const bool plane_stated = config.source_plane_normal != Vec3::Zero();
    localization = volumetric || (linear && plane_stated) ? Localization::kPosition : Localization::kDirection;
  }
  // A volumetric array follows one source with its tracker unless the config states
  // several (max_sources >= 2): then each source by direction, with its own position.
  // (No side or plane is needed, so nothing more to check here: DirectionStage builds the fit.)
  const bool several = volumetric && localization == Localization::kPosition && config.max_sources >= 2;
  if (localization == Localization::kPosition && !volumetric) {
    const size_t needed = linear ? 3 : 4;
    if (config.sensors_m.size() < needed) {
      return InvalidArgument("array.sensors_m has " + std::to_string(config.sensors_m.size()) +
                             " sensors; localization position with a " + ArrayShapeName(shape->shape) +
                             " array needs " + std::to_string(needed) + " or more (or use localization direction)");
    }
    auto locator = NearFieldLocator::Create(config.sensors_m, NearFieldOptionsFor(config));
    if (!locator.ok()) return InvalidArgument(locator.status().message() + " (or use localization direction)");
  }
  return Resolved{*shape, localization, localization == Localization::kDirection || !volumetric || several};
}

}  // namespace

StatusOr<Localization> ResolveLocalization(const AudioSessionConfig& config) {
  auto resolved = Resolve(config);
  if (!resolved.ok()) return resolved.status();
  return resolved->localization;
}

StatusOr<bool> ReportsSources(const AudioSessionConfig& config) {
  auto resolved = Resolve(config);
  if (!resolved.ok()) return resolved.status();
  return resolved->sources;
}

StatusOr<std::unique_ptr<Session>> Session::Create(const AudioSessionConfig& config) {
  LOCALIZER_RETURN_IF_ERROR(config.Validate());
  auto resolved = Resolve(config);
  if (!resolved.ok()) return resolved.status();
  const auto& [shape, localization, sources] = *resolved;
  if (sources) {
    if (config.array_in_body_frame) {
      return InvalidArgument(std::string("localization ") + LocalizationName(localization) + " with a " +
                             ArrayShapeName(shape.shape) + " array does not take a moving array (platform) yet");
    }
    auto stage = DirectionStage::Create(config, localization == Localization::kPosition);
    if (!stage.ok()) return stage.status();
    auto direction = std::make_unique<DirectionImpl>(config, std::move(stage).value());
    return std::unique_ptr<Session>(new Session(shape, localization, nullptr, std::move(direction)));
  }
  auto array = ArrayGeometry::Create(config.sensors_m, config.sound_speed_mps, config.reference_sensor);
  if (!array.ok()) return array.status();
  TrackerOptions tracker = config.tracker;
  tracker.particle.seed = config.seed;
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
  auto parts = BuildComponents(config.backend, *array, config.GccOptionsFor(), tracker, config.array_in_body_frame);
  if (!parts.ok()) return parts.status();
  parts->tracker->SetBounds(config.bounds_min_m, config.bounds_max_m);
  return std::unique_ptr<Session>(
      new Session(shape, localization,
                  std::make_unique<Impl>(config, std::move(array).value(), std::move(parts).value(), std::move(pose),
                                         std::move(acquisition).value()),
                  nullptr));
}

Status Session::Process(const BlockView& block, std::vector<Estimate>* out) {
  if (direction_ != nullptr) {
    DirectionImpl& d = *direction_;
    LOCALIZER_RETURN_IF_ERROR(
        ValidateBlock(block, sensor_count(), d.config.max_block_samples, d.have_sequence, d.last_sequence));
    d.have_sequence = true;
    d.last_sequence = block.sequence;
    d.framer.Append(block);
    const float* frame = nullptr;
    int64_t first = 0;
    while (d.framer.Next(&frame, &first)) {
      Estimate e;
      e.frame_index = d.frames++;
      e.sequence = block.sequence;
      e.t_s = FrameCentre_s(first, d.config);
      const auto start = std::chrono::steady_clock::now();
      d.stage->Frame(frame, e.t_s, &e);
      e.timings.tdoa_s = SecondsSince(start);  // the spatial spectrum and the tracker
      out->push_back(std::move(e));
    }
    return Status::Ok();
  }
  Impl& s = *impl_;
  LOCALIZER_RETURN_IF_ERROR(
      ValidateBlock(block, s.array.sensor_count(), s.config.max_block_samples, s.have_sequence, s.last_sequence));
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
  (direction_ != nullptr ? direction_->framer : impl_->framer).Skip(samples_per_channel);
  return Status::Ok();
}

Status Session::AddImu(const std::vector<ImuSample>& samples) {
  if (impl_ == nullptr || impl_->platform == nullptr) {
    return FailedPrecondition(
        "IMU samples for a session whose array is fixed in the world "
        "(open it with the array in the platform's body frame)");
  }
  return impl_->platform->Add(samples);
}

Status Session::SetPlatformOrigin(const Vec3& origin_m) {
  if (impl_ == nullptr || impl_->platform == nullptr) {
    return FailedPrecondition("platform origin for a session whose array is fixed in the world");
  }
  return impl_->platform->SetOrigin(origin_m);
}

const AudioSessionConfig& Session::config() const { return direction_ != nullptr ? direction_->config : impl_->config; }
const std::string& Session::backend() const {
  return direction_ != nullptr ? direction_->backend : impl_->components.backend;
}
const ArrayGeometry* Session::geometry() const { return impl_ != nullptr ? &impl_->array : nullptr; }
uint64_t Session::frames_processed() const { return direction_ != nullptr ? direction_->frames : impl_->frames; }

}  // namespace localizer::engine
