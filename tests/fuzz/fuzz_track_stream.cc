// A Track stream: the input is a sequence of TrackRequests, each preceded by its length as a
// varint (protobuf's delimited format), decoded as the server decodes a stream: `open` through
// ConfigFromProto; `resume` through the length limits on its strings; `block`, `imu` and
// `scan` through the decoders of the opened session's kind, against its limits
// (SessionRunner::Decode, AudioRunner, DetectionRunner). Requests before a successful open
// are decoded against a default 4-sensor audio config (the server would refuse them) so that
// the data decoders are reached without a valid open. At most 64 requests per input.
#include <google/protobuf/io/zero_copy_stream_impl_lite.h>
#include <google/protobuf/util/delimited_message_util.h>

#include <optional>

#include "fuzz_checks.h"
#include "wire/stream_wire.h"
#include "wire/string_limits.h"

namespace {

using namespace localizer;

void CheckRejection(const char* request, uint64_t sequence, const std::string& reason, const Status& status) {
  fuzz::CheckRefusal(status, request);
  v1::BlockRejected rejected;
  wire::RejectionToProto(request, sequence, reason, status, &rejected);
  FUZZ_CHECK(rejected.code() == "INVALID_ARGUMENT" && rejected.message() == status.message() &&
                 rejected.reason() == reason && rejected.sequence() == sequence,
             rejected.ShortDebugString());
}

void CheckEscaped(const std::string& value) {
  const std::string prefix = wire::EscapedPrefix(value);
  FUZZ_CHECK(prefix.size() <= 16 * 4 + 3, std::to_string(prefix.size()));
  for (const char ch : prefix) {
    const auto u = static_cast<unsigned char>(ch);
    FUZZ_CHECK(u >= 0x20 && u < 0x7f, "EscapedPrefix left a raw byte " + std::to_string(u));
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  google::protobuf::io::ArrayInputStream input(data, static_cast<int>(size));
  const wire::ConfigPolicy policy = fuzz::FuzzPolicy();
  static const engine::SessionConfig kDefault = *wire::ConfigFromProto(fuzz::TetraConfig(), policy);
  std::optional<engine::SessionConfig> opened;
  wire::DecodedBlock scratch;  // one per stream, reused between blocks as the reactor's
  for (int n = 0; n < 64; ++n) {
    v1::TrackRequest request;
    bool clean_eof = false;
    if (!google::protobuf::util::ParseDelimitedFromZeroCopyStream(&request, &input, &clean_eof)) break;
    const engine::SessionConfig& config = opened ? *opened : kDefault;
    const auto* audio = std::get_if<engine::AudioSessionConfig>(&config);
    switch (request.kind_case()) {
      case v1::TrackRequest::kOpen: {
        auto decoded = wire::ConfigFromProto(request.open(), policy);
        if (!decoded.ok()) {
          fuzz::CheckRefusal(decoded.status(), "open");
          return 0;  // the stream ends
        }
        fuzz::CheckAcceptedConfig(*decoded, policy);
        if (opened) return 0;  // a second open ends the stream too
        opened = *std::move(decoded);
        break;
      }
      case v1::TrackRequest::kResume: {
        const v1::ResumeSession& resume = request.resume();
        const Status id = wire::CheckLength("session_id", resume.session_id(), wire::kMaxSessionIdBytes);
        const Status token = wire::CheckLength("resume_token", resume.resume_token(), wire::kMaxResumeTokenBytes);
        FUZZ_CHECK(id.ok() == (resume.session_id().size() <= wire::kMaxSessionIdBytes), "session_id limit");
        FUZZ_CHECK(token.ok() == (resume.resume_token().size() <= wire::kMaxResumeTokenBytes), "token limit");
        if (!id.ok()) fuzz::CheckRefusal(id, "resume.session_id");
        if (!token.ok()) fuzz::CheckRefusal(token, "resume.resume_token");
        CheckEscaped(resume.session_id());
        CheckEscaped(resume.resume_token());
        break;
      }
      case v1::TrackRequest::kBlock: {
        if (audio == nullptr) break;  // a detection session refuses blocks unread (not_samples)
        const wire::BlockLimits limits{static_cast<int>(audio->sensors_m.size()), audio->max_block_samples};
        std::string reason;
        const Status status = wire::DecodeBlock(request.block(), limits, &scratch, &reason);
        if (status.ok()) {
          fuzz::CheckDecodedBlock(request.block(), limits, scratch);
        } else {
          CheckRejection("block", request.block().sequence(), reason, status);
        }
        break;
      }
      case v1::TrackRequest::kImu: {
        // A fixed array refuses IMU batches unread (not_moving); decoded anyway here, as the
        // decoder is the same for every session.
        auto decoded = wire::DecodeImuBatch(request.imu());
        if (decoded.ok()) {
          fuzz::CheckDecodedImu(request.imu(), *decoded);
        } else {
          CheckRejection("imu", request.imu().sequence(), "imu", decoded.status());
        }
        break;
      }
      case v1::TrackRequest::kScan: {
        if (audio != nullptr && opened) break;  // an audio session refuses scans unread (not_detections)
        auto decoded = wire::DecodeScan(request.scan());
        if (decoded.ok()) {
          fuzz::CheckDecodedScan(request.scan(), *decoded);
        } else {
          CheckRejection("scan", request.scan().sequence(), "scan", decoded.status());
        }
        break;
      }
      default:
        return 0;  // "TrackRequest has no open, resume, block, imu or scan": the stream ends
    }
  }
  return 0;
}
