// Streams samples through an open TrackStream and collects what comes back: the loop of
// `localizer-cli track --server` and `simulate --server`.
//
// A writer thread pulls up to `block_samples` samples per channel from the source, encodes
// them (wire::EncodeBlock: float32, or 16-bit PCM clipped at +-1) with sequence numbers
// first_sequence, first_sequence + 1, ... and writes them:
//   Pacing::kMax       as fast as the stream takes them (gRPC flow control pushes back);
//   Pacing::kRealtime  block k (holding samples [a, b) per channel) is written at
//                      start + b / sample_rate_hz, on an absolute schedule: the moment a
//                      live array would have recorded its last sample. Late writes do not
//                      shift later ones, so the average rate stays exact.
// At the end of the source it half-closes (WritesDone: "finished"), also when the source
// fails (its error is reported, and the server still answers what was sent).
// The calling thread reads every response until the stream ends, then joins the writer
// and calls Finish. Per estimate it measures the client latency: from the moment the block
// that completed the frame (Estimate.sequence) was handed to Write to the moment the
// estimate was read; frames completed by one block share its send time.
//
// Callbacks run on the calling thread, in arrival order, and may block only briefly (they
// hold up reading, so the server's flow control eventually holds up its estimates).
// The source runs on the writer thread; it must not touch what the callbacks touch.
#pragma once

#include <grpcpp/support/status.h>

#include <cstdint>
#include <functional>
#include <limits>
#include <string>
#include <vector>

#include "clients/grpc/track_stream.h"
#include "engine/core/estimate.h"
#include "engine/core/status.h"
#include "localizer/v1/localizer.pb.h"

namespace localizer::client {

// Fills `channel_major` (resized to channel_count * n, channel c at [c * n, (c + 1) * n))
// with the next n <= max_samples_per_channel samples per channel and returns n; 0 at the
// end. io::SampleStream::Read (WAV files, raw PCM) has this shape.
using SampleSource =
    std::function<StatusOr<int64_t>(int64_t max_samples_per_channel, std::vector<float>* channel_major)>;

// A source over channel-major samples held by the caller (channel c at
// [c * samples_per_channel, (c + 1) * samples_per_channel)), which must outlive it.
SampleSource ChannelMajorSource(const float* samples, int channel_count, int64_t samples_per_channel);

enum class Pacing { kMax, kRealtime };
enum class Encoding { kFloat32, kPcm16 };

// "max" | "realtime"; "float" | "pcm16". INVALID_ARGUMENT naming the valid values.
StatusOr<Pacing> ParsePacing(const std::string& name);
StatusOr<Encoding> ParseEncoding(const std::string& name);

struct StreamOptions {
  int channel_count = 0;         // the array's sensor count, >= 1
  double sample_rate_hz = 0.0;   // samples per second per channel, > 0 (paces kRealtime)
  int64_t block_samples = 4096;  // per channel per block, >= 1
  Pacing pacing = Pacing::kMax;
  Encoding encoding = Encoding::kFloat32;
  uint64_t first_sequence = 1;  // >= 1; a resumed stream continues after last_sequence

  Status Validate() const;  // INVALID_ARGUMENT naming the field
};

struct StreamedEstimate {
  engine::Estimate estimate;  // wire::EstimateFromProto; timings are the server's stage times
  double queue_s = 0.0;       // server: the completing block's wait for a worker
  double total_s = 0.0;       // server: block received -> estimate ready
  // This client: block handed to Write -> estimate read, s. NaN when the block was not
  // written on this stream (an estimate resent after a resume).
  double client_latency_s = std::numeric_limits<double>::quiet_NaN();
  std::string backend;  // "cpu" or "gpu"
};

struct BlockRejection {
  uint64_t sequence = 0;
  std::string code;     // gRPC code name, "INVALID_ARGUMENT"
  std::string reason;   // short key: channel_count, non_finite, oversize, queue_full, ...
  std::string message;  // names the field and the value
};

struct StreamResult {
  std::vector<StreamedEstimate> estimates;  // in arrival order (frame order)
  std::vector<BlockRejection> rejections;
  std::vector<v1::SequenceGap> gaps;
  uint64_t blocks_sent = 0;  // Write calls that succeeded
  int64_t samples_sent_per_channel = 0;
  double wall_s = 0.0;       // start of streaming -> stream ended
  grpc::Status grpc_status;  // the stream's final status
  Status client_status;      // bad options or a failing source, else OK

  // OK when both are; else client_status, else the stream's (wire::FromGrpcStatus).
  Status status() const;
  std::vector<engine::Estimate> Estimates() const;
  std::vector<double> ClientLatencies() const;  // seconds, one per estimate
};

struct StreamCallbacks {
  std::function<void(const StreamedEstimate&)> on_estimate;
  std::function<void(const BlockRejection&)> on_rejected;
  std::function<void(const v1::SequenceGap&)> on_gap;
};

// Runs the loop above on `stream` (opened, nothing written yet) and finishes it. Invalid
// options cancel the stream and come back as client_status. Never throws.
StreamResult StreamBlocks(TrackStream& stream, const SampleSource& source, const StreamOptions& options,
                          const StreamCallbacks& callbacks = {});

}  // namespace localizer::client
