// localizer-cli locate: one block of a recording through the server's one-shot Locate.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>

#include "clients/cli/commands.h"
#include "clients/cli/server_flags.h"
#include "clients/cli/session_flags.h"
#include "clients/grpc/connection.h"
#include "clients/io/array_json.h"
#include "clients/io/wav_io.h"
#include "localizer/v1/localizer.grpc.pb.h"
#include "wire/block_wire.h"
#include "wire/config_wire.h"
#include "wire/status_wire.h"

namespace localizer::cli {

namespace {

const char* const kCommand = "locate";

struct Segment {
  std::vector<float> samples;  // channel-major
  int channel_count = 0;
  int64_t samples_per_channel = 0;
  double sample_rate_hz = 0.0;
};

// Samples [start, start + length) per channel of the recording, fewer at its end.
StatusOr<Segment> ReadSegment(const std::vector<std::string>& paths, double start_s, double duration_s) {
  auto stream = io::WavStream::Open(paths);
  if (!stream.ok()) return stream.status();
  const double fs = stream->sample_rate_hz();
  const auto start = static_cast<int64_t>(std::llround(start_s * fs));
  const auto length = static_cast<int64_t>(std::llround(duration_s * fs));
  if (start >= stream->total_frames()) {
    return OutOfRange(stream->Describe() + " is " + FormatDouble(static_cast<double>(stream->total_frames()) / fs) +
                      " s long; --start-s " + FormatDouble(start_s) + " is past its end");
  }
  std::vector<float> chunk;
  for (int64_t skipped = 0; skipped < start;) {
    auto n = stream->Read(std::min<int64_t>(start - skipped, 1 << 16), &chunk);
    if (!n.ok()) return n.status();
    skipped += *n;
  }
  // Read in chunks, then assemble channel-major (each chunk is channel-major too).
  std::vector<std::vector<float>> chunks;
  std::vector<int64_t> sizes;
  int64_t total = 0;
  while (total < length) {
    auto n = stream->Read(length - total, &chunk);
    if (!n.ok()) return n.status();
    if (*n == 0) break;
    chunks.push_back(chunk);
    sizes.push_back(*n);
    total += *n;
  }
  Segment segment;
  segment.channel_count = stream->channel_count();
  segment.samples_per_channel = total;
  segment.sample_rate_hz = fs;
  segment.samples.resize(static_cast<size_t>(segment.channel_count * total));
  int64_t at = 0;
  for (size_t i = 0; i < chunks.size(); ++i) {
    for (int c = 0; c < segment.channel_count; ++c) {
      std::copy(chunks[i].begin() + c * sizes[i], chunks[i].begin() + (c + 1) * sizes[i],
                segment.samples.begin() + c * total + at);
    }
    at += sizes[i];
  }
  return segment;
}

void PrintResponse(const v1::LocateResponse& r) {
  for (const v1::PairTdoa& pair : r.pairs()) {
    std::printf("pair sensor=%u delay_us=%.3f quality=%.3f peak_snr=%.2f\n", pair.sensor(), pair.delay_s() * 1e6,
                pair.quality(), pair.peak_snr());
  }
  if (!r.fix_found()) {
    std::printf("no fix residual_rms_us=%.3f tdoa_ms=%.3f\n", r.residual_rms_s() * 1e6, r.tdoa_s() * 1e3);
    return;
  }
  const auto sd = [&r](int axis) {
    return r.covariance_size() == 9 ? std::sqrt(std::max(0.0, r.covariance(4 * axis))) : NAN;
  };
  std::printf(
      "fix x_m=%.3f y_m=%.3f z_m=%.3f sx_m=%.3f sy_m=%.3f sz_m=%.3f residual_rms_us=%.3f "
      "tdoa_ms=%.3f\n",
      r.position_m().x(), r.position_m().y(), r.position_m().z(), sd(0), sd(1), sd(2), r.residual_rms_s() * 1e6,
      r.tdoa_s() * 1e3);
}

}  // namespace

int RunLocate(const std::vector<std::string>& args) {
  std::string server;
  client::ConnectOptions connect;
  std::string array_path;
  std::vector<std::string> wav_paths;
  double start_s = 0.0;
  double duration_s = 1.0;
  double timeout_s = 30.0;
  SessionFlags session;
  FlagSet flags(
      "localizer-cli locate --server HOST:PORT --array FILE --wav FILE [--start-s S] "
      "[--duration-s D]",
      "Sends one block of a recording (--duration-s from --start-s) to the server's one-shot\n"
      "Locate: the whole block is one GCC frame. Prints each sensor pair (reference, k) as\n"
      "delay, quality (peak / strongest sidelobe) and peak SNR, then the multilateration\n"
      "fix with its standard deviations, or \"no fix\". Nothing is tracked or kept.");
  RegisterServerFlag(flags, &server, /*required=*/true, &connect);
  flags.String("array", &array_path, "FILE", "sensor array: array.json, or the XAV hydrophones_config CSV").Required();
  flags.Strings("wav", &wav_paths, "FILE", "one multichannel WAV, or one mono WAV per sensor in sensor order")
      .Required();
  flags.Double("start-s", &start_s, "S", "s", "start of the block in the recording");
  flags.Double("duration-s", &duration_s, "S", "s", "length of the block (cut short at the end of the recording)");
  RegisterGccFlags(flags, &session);
  flags.Double("timeout", &timeout_s, "S", "s", "deadline of the call");
  if (auto exit_code = ParseFlagsOrExit(kCommand, flags, args)) return *exit_code;
  if (!(start_s >= 0.0)) return UsageError(kCommand, "--start-s must be >= 0");
  if (!(duration_s > 0.0)) return UsageError(kCommand, "--duration-s must be > 0");
  if (!(timeout_s > 0.0)) return UsageError(kCommand, "--timeout must be > 0");

  auto array = io::ReadArrayFile(array_path);
  if (!array.ok()) return RuntimeError(kCommand, array.status());
  auto segment = ReadSegment(wav_paths, start_s, duration_s);
  if (!segment.ok()) return RuntimeError(kCommand, segment.status());
  if (segment->channel_count != static_cast<int>(array->sensors_m.size())) {
    return RuntimeError(
        kCommand, InvalidArgument("the recording has " + std::to_string(segment->channel_count) + " channels but " +
                                  array_path + " has " + std::to_string(array->sensors_m.size()) + " sensors"));
  }
  auto config = BuildSessionConfig(session, flags, *array, segment->sample_rate_hz, Runs::kOnServer);
  if (!config.ok()) return UsageError(kCommand, config.status().message());

  v1::LocateRequest request;
  *request.mutable_config() = wire::ConfigToProto(*config, "");
  request.mutable_config()->set_max_block_samples(0);
  engine::BlockView view;
  view.sequence = 1;
  view.channel_count = segment->channel_count;
  view.samples_per_channel = segment->samples_per_channel;
  view.samples = segment->samples.data();
  wire::EncodeBlock(view, /*pcm16=*/false, request.mutable_block());

  auto channel = client::Connect(server, connect);
  if (!channel.ok()) return RuntimeError(kCommand, channel.status());
  auto stub = v1::Localizer::NewStub(*channel);
  grpc::ClientContext context;
  context.set_deadline(
      std::chrono::system_clock::now() +
      std::chrono::duration_cast<std::chrono::system_clock::duration>(std::chrono::duration<double>(timeout_s)));
  v1::LocateResponse response;
  const grpc::Status status = stub->Locate(&context, request, &response);
  if (!status.ok()) return RuntimeError(kCommand, wire::FromGrpcStatus(status));
  PrintResponse(response);
  return kExitOk;
}

}  // namespace localizer::cli
