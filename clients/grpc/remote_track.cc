#include "clients/grpc/remote_track.h"

#include <atomic>
#include <chrono>
#include <optional>
#include <utility>

#include "clients/grpc/track_stream.h"
#include "engine/pipeline/session.h"
#include "wire/config_wire.h"

namespace localizer::client {

StatusOr<std::unique_ptr<TrackStream>> OpenTrackSession(const std::shared_ptr<grpc::Channel>& channel,
                                                        const engine::AudioSessionConfig& config,
                                                        const std::string& label, const std::string& session_key) {
  v1::SessionConfig proto = wire::ConfigToProto(config, label);
  proto.set_max_block_samples(0);  // the server's limit; it bounds block size, not numbers
  return TrackStream::Open(channel, proto, session_key);
}

StatusOr<RemoteTrackResult> RunRemoteTrack(const std::shared_ptr<grpc::Channel>& channel, const io::TrackJob& job,
                                           const RemoteTrackOptions& options, const io::TrackCallbacks& callbacks,
                                           const StreamCallbacks& stream_callbacks) {
  auto prepared = io::PrepareTrack(job, callbacks);
  if (!prepared.ok()) return prepared.status();
  const engine::AudioSessionConfig& config = prepared->config;
  LOCALIZER_RETURN_IF_ERROR(config.Validate());
  auto sources = engine::ReportsSources(config);
  if (!sources.ok()) return sources.status();
  std::optional<engine::ArrayGeometry> array;  // the tracker's positions: names the CSV's pair columns
  if (!*sources) {
    auto made = engine::ArrayGeometry::Create(config.sensors_m, config.sound_speed_mps, config.reference_sensor);
    if (!made.ok()) return made.status();
    array = std::move(made).value();
  }
  StreamOptions stream_options;
  stream_options.channel_count = prepared->stream->channel_count();
  stream_options.sample_rate_hz = prepared->stream->sample_rate_hz();
  stream_options.block_samples = options.block_samples;
  stream_options.pacing = options.pacing;
  stream_options.encoding = options.encoding;
  LOCALIZER_RETURN_IF_ERROR(stream_options.Validate());
  auto writer = io::OpenEstimatesWriter(job.estimates_path, job.estimates_format, array ? &*array : nullptr,
                                       job.geodetic_origin);
  if (!writer.ok()) return writer.status();

  auto stream = OpenTrackSession(channel, config, options.label, options.session_key);
  if (!stream.ok()) return stream.status();

  RemoteTrackResult result;
  result.opened = (*stream)->opened();
  result.sample_rate_hz = stream_options.sample_rate_hz;
  if (options.on_opened) options.on_opened(result.opened);

  // The source runs on the writer thread; the reader reports progress from this counter.
  io::SampleStream& input = *prepared->stream;
  std::atomic<int64_t> samples_read{0};
  const SampleSource source = [&input, &samples_read](int64_t max_samples,
                                                      std::vector<float>* out) -> StatusOr<int64_t> {
    auto n = input.Read(max_samples, out);
    if (n.ok()) samples_read += *n;
    return n;
  };
  const int64_t total_samples = input.total_frames();
  const auto start = std::chrono::steady_clock::now();
  Status csv_status;
  TrackStream& track_stream = **stream;
  StreamCallbacks reader = stream_callbacks;
  reader.on_estimate = [&](const StreamedEstimate& e) {
    if (csv_status.ok() && *writer) {
      csv_status = (*writer)->Write(e.estimate);
      if (!csv_status.ok()) track_stream.Cancel();
    }
    if (callbacks.on_estimate) callbacks.on_estimate(e.estimate);
    if (stream_callbacks.on_estimate) stream_callbacks.on_estimate(e);
    if (callbacks.on_progress) {
      const double wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      callbacks.on_progress(
          io::TrackProgress{samples_read.load(), total_samples, stream_options.sample_rate_hz, wall_s});
    }
  };
  result.stream = StreamBlocks(track_stream, source, stream_options, reader);
  if (!csv_status.ok()) return csv_status;
  if (*writer) LOCALIZER_RETURN_IF_ERROR((*writer)->Close());
  return result;
}

}  // namespace localizer::client
