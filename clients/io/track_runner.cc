#include "clients/io/track_runner.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <memory>

#include "clients/io/csv_io.h"
#include "clients/io/raw_pcm.h"
#include "clients/io/wav_io.h"

namespace localizer::io {

namespace {

using Clock = std::chrono::steady_clock;

double SecondsSince(Clock::time_point start) { return std::chrono::duration<double>(Clock::now() - start).count(); }

void Warn(const TrackCallbacks& callbacks, const std::string& message) {
  if (callbacks.on_warning) callbacks.on_warning(message);
}

// The session config with the input's sample rate, after checking the input against the array.
StatusOr<engine::AudioSessionConfig> ConfigForStream(const TrackJob& job, const SampleStream& stream,
                                                     const TrackCallbacks& callbacks) {
  const int sensors = static_cast<int>(job.config.sensors_m.size());
  if (stream.channel_count() != sensors) {
    return InvalidArgument(stream.Describe() + " has " + std::to_string(stream.channel_count()) + " channels but " +
                           job.array_source + " has " + std::to_string(sensors) +
                           " sensors; they must match (channel k = "
                           "sensor k)");
  }
  engine::AudioSessionConfig config = job.config;
  config.sample_rate_hz = stream.sample_rate_hz();
  if (job.array_sample_rate_hz && *job.array_sample_rate_hz != stream.sample_rate_hz()) {
    Warn(callbacks, job.array_source + " says sample_rate_hz " + std::to_string(*job.array_sample_rate_hz) + " but " +
                        stream.Describe() + " is sampled at " + std::to_string(stream.sample_rate_hz()) +
                        " Hz; using " + stream.RateOrigin());
  }
  return config;
}

// One run: the stream, the session and the writer, fed block by block.
class TrackRun {
 public:
  TrackRun(std::unique_ptr<SampleStream> stream, std::unique_ptr<engine::Session> session,
           std::unique_ptr<EstimatesWriter> writer, const TrackCallbacks& callbacks)
      : stream_(std::move(stream)), session_(std::move(session)), writer_(std::move(writer)), callbacks_(callbacks) {}

  StatusOr<TrackSummary> Run(double block_s) {
    summary_.sample_rate_hz = stream_->sample_rate_hz();
    summary_.channel_count = stream_->channel_count();
    const int64_t block_frames = std::max<int64_t>(1, std::llround(block_s * stream_->sample_rate_hz()));
    const Clock::time_point start = Clock::now();
    while (true) {
      auto frames = stream_->Read(block_frames, &samples_);
      if (!frames.ok()) return frames.status();
      if (*frames == 0) break;
      LOCALIZER_RETURN_IF_ERROR(SkipLost(stream_->frames_lost_before_last_read()));
      LOCALIZER_RETURN_IF_ERROR(ProcessBlock(*frames));
      ReportProgress(start);
    }
    if (writer_) LOCALIZER_RETURN_IF_ERROR(writer_->Close());
    summary_.wall_s = SecondsSince(start);
    summary_.overruns = stream_->overrun_count();
    if (summary_.estimates > 0) {
      summary_.mean_tdoa_s = tdoa_total_s_ / static_cast<double>(summary_.estimates);
      summary_.mean_filter_s = filter_total_s_ / static_cast<double>(summary_.estimates);
    }
    return summary_;
  }

 private:
  // The input lost `frames` before the block just read: the session's clock jumps over them.
  Status SkipLost(int64_t frames) {
    if (frames <= 0) return Status::Ok();
    LOCALIZER_RETURN_IF_ERROR(session_->Skip(frames));
    summary_.frames_lost += frames;
    return Status::Ok();
  }

  Status ProcessBlock(int64_t frames) {
    engine::BlockView block;
    block.sequence = ++summary_.blocks;
    block.channel_count = stream_->channel_count();
    block.samples_per_channel = frames;
    block.samples = samples_.data();
    estimates_.clear();
    const Status status = session_->Process(block, &estimates_);
    if (!status.ok()) {
      const double at_s =
          static_cast<double>(summary_.samples_per_channel + summary_.frames_lost) / summary_.sample_rate_hz;
      return Status(status.code(), stream_->Describe() + ": block " + std::to_string(block.sequence) + " at " +
                                       std::to_string(at_s) + " s rejected: " + status.message());
    }
    summary_.samples_per_channel += frames;
    for (const engine::Estimate& e : estimates_) LOCALIZER_RETURN_IF_ERROR(Consume(e));
    return Status::Ok();
  }

  Status Consume(const engine::Estimate& e) {
    ++summary_.estimates;
    if (e.initialised) ++summary_.initialised_estimates;
    summary_.presence.Add(e);
    tdoa_total_s_ += e.timings.tdoa_s;
    filter_total_s_ += e.timings.filter_s;
    if (writer_) LOCALIZER_RETURN_IF_ERROR(writer_->Write(e));
    if (callbacks_.on_estimate) callbacks_.on_estimate(e);
    return Status::Ok();
  }

  void ReportProgress(Clock::time_point start) const {
    if (!callbacks_.on_progress) return;
    callbacks_.on_progress(TrackProgress{summary_.samples_per_channel, stream_->total_frames(), summary_.sample_rate_hz,
                                         SecondsSince(start)});
  }

  std::unique_ptr<SampleStream> stream_;
  std::unique_ptr<engine::Session> session_;
  std::unique_ptr<EstimatesWriter> writer_;
  const TrackCallbacks& callbacks_;
  std::vector<float> samples_;               // one block, channel-major; reused
  std::vector<engine::Estimate> estimates_;  // one block's estimates; reused
  TrackSummary summary_;
  double tdoa_total_s_ = 0.0;
  double filter_total_s_ = 0.0;
};

// The second half of RunTrack: the session and the writer for a prepared input, and the run.
// `built`, when not null, was built from job.config; it serves when the input left the
// config as it was (ConfigForStream sets only the sample rate).
StatusOr<TrackSummary> RunPrepared(PreparedTrack prepared, const TrackJob& job, const TrackCallbacks& callbacks,
                                   std::unique_ptr<engine::Session> built = nullptr) {
  if (callbacks.on_opened) callbacks.on_opened(*prepared.stream);
  if (built == nullptr || built->config().sample_rate_hz != prepared.config.sample_rate_hz) {
    auto session = engine::Session::Create(prepared.config);
    if (!session.ok()) return session.status();
    built = std::move(*session);
  }
  auto writer = OpenEstimatesWriter(job.estimates_path, job.estimates_format, built->geometry(), job.geodetic_origin);
  if (!writer.ok()) return writer.status();
  TrackRun run(std::move(prepared.stream), std::move(built), std::move(*writer), callbacks);
  return run.Run(job.block_s);
}

Status CheckBlock(const TrackJob& job) {
  if (!(job.block_s > 0.0 && std::isfinite(job.block_s))) {
    return InvalidArgument("block_s is " + std::to_string(job.block_s) + ", must be > 0");
  }
  return Status::Ok();
}

}  // namespace

StatusOr<TrackSummary> RunTrack(const TrackJob& job, const TrackCallbacks& callbacks,
                                std::unique_ptr<engine::Session> session) {
  LOCALIZER_RETURN_IF_ERROR(CheckBlock(job));
  auto prepared = PrepareTrack(job, callbacks);
  if (!prepared.ok()) return prepared.status();
  return RunPrepared(std::move(*prepared), job, callbacks, std::move(session));
}

StatusOr<TrackSummary> RunTrackOn(std::unique_ptr<SampleStream> stream, const TrackJob& job,
                                  const TrackCallbacks& callbacks) {
  LOCALIZER_RETURN_IF_ERROR(CheckBlock(job));
  if (stream == nullptr) return InvalidArgument("RunTrackOn: no input stream");
  auto config = ConfigForStream(job, *stream, callbacks);
  if (!config.ok()) return config.status();
  return RunPrepared(PreparedTrack{std::move(stream), std::move(*config)}, job, callbacks);
}

engine::AudioSessionConfig TrackConfigFor(engine::AudioSessionConfig config, const ArrayFile& array,
                                          const ArrayOverrides& overrides, double sample_rate_hz) {
  config.sensors_m = array.sensors_m;
  config.sound_speed_mps = overrides.sound_speed_mps.value_or(array.sound_speed_mps);
  config.reference_sensor = overrides.reference_sensor.value_or(array.reference_sensor);
  config.sample_rate_hz = sample_rate_hz;
  if (config.band_low_hz == 0.0 && config.band_high_hz == 0.0 && array.band_hz) {
    config.band_low_hz = array.band_hz->first;  // the array file's hint, unless flags say
    config.band_high_hz = std::min(array.band_hz->second, 0.5 * sample_rate_hz);
  }
  const bool base_unbounded =
      !config.bounds_min_m.array().isFinite().any() && !config.bounds_max_m.array().isFinite().any();
  if (base_unbounded && array.has_bounds()) {
    config.bounds_min_m = array.bounds_min_m;
    config.bounds_max_m = array.bounds_max_m;
  }
  // ArrayFile::Localization lists the names in engine::Localization's order.
  config.localization = static_cast<engine::Localization>(static_cast<int>(array.localization));
  if (array.max_sources) config.max_sources = *array.max_sources;
  if (array.source_side_normal) config.source_side = *array.source_side_normal;
  if (array.source_plane) {
    config.source_plane_point_m = array.source_plane->point_m;
    config.source_plane_normal = array.source_plane->normal;
  }
  if (overrides.bounds_min_m) config.bounds_min_m = *overrides.bounds_min_m;
  if (overrides.bounds_max_m) config.bounds_max_m = *overrides.bounds_max_m;
  if (overrides.bottom_z_m) config.bounds_min_m.z() = *overrides.bottom_z_m;
  if (overrides.surface_z_m) config.bounds_max_m.z() = *overrides.surface_z_m;
  return config;
}

namespace {

StatusOr<std::unique_ptr<SampleStream>> OpenInput(const TrackJob& job, const TrackCallbacks& callbacks) {
  if (job.alsa) {
    auto alsa = AlsaCaptureStream::Open(*job.alsa);
    if (!alsa.ok()) return alsa.status();
    return std::unique_ptr<SampleStream>(std::move(*alsa));
  }
  if (job.raw) {
    auto raw = RawPcmStream::Open(*job.raw);
    if (!raw.ok()) return raw.status();
    return std::unique_ptr<SampleStream>(std::move(*raw));
  }
  auto wav = WavStream::Open(job.wav_paths);
  if (!wav.ok()) return wav.status();
  if (!wav->warning().empty()) Warn(callbacks, wav->warning());
  return std::unique_ptr<SampleStream>(std::make_unique<WavStream>(std::move(*wav)));
}

}  // namespace

StatusOr<PreparedTrack> PrepareTrack(const TrackJob& job, const TrackCallbacks& callbacks) {
  auto stream = OpenInput(job, callbacks);
  if (!stream.ok()) return stream.status();
  auto config = ConfigForStream(job, **stream, callbacks);
  if (!config.ok()) return config.status();
  return PreparedTrack{std::move(*stream), std::move(*config)};
}

}  // namespace localizer::io
