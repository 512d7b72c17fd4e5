#include "server/service/session_runner.h"

#include "server/service/audio_runner.h"
#include "server/service/detection_runner.h"
#include "wire/stream_wire.h"

namespace localizer::server {

StatusOr<std::unique_ptr<SessionRunner>> MakeSessionRunner(const engine::SessionConfig& config,
                                                           ServiceMetrics* metrics) {
  // The one question of kind: a detection config opens a detection session.
  if (const auto* detection = std::get_if<engine::DetectionSessionConfig>(&config)) {
    auto scans = engine::ScanSession::Create(*detection);
    if (!scans.ok()) return scans.status();
    return std::unique_ptr<SessionRunner>(std::make_unique<DetectionRunner>(std::move(scans).value(), metrics));
  }
  auto session = engine::Session::Create(std::get<engine::AudioSessionConfig>(config));
  if (!session.ok()) return session.status();
  return std::unique_ptr<SessionRunner>(std::make_unique<AudioRunner>(std::move(session).value(), metrics));
}

WorkItem SessionRunner::Decode(const v1::TrackRequest& request, Clock::time_point received,
                               wire::DecodedBlock* scratch) const {
  switch (request.kind_case()) {
    case v1::TrackRequest::kBlock:
      return DecodeBlock(request.block(), received, scratch);
    case v1::TrackRequest::kImu:
      return DecodeImu(request.imu(), received);
    case v1::TrackRequest::kScan:
      return DecodeScan(request.scan(), received);
    default:
      break;
  }
  return {Rejection{RequestKind::kBlock, 0, "bad_request", InvalidArgument("TrackRequest has no block, imu or scan")},
          received};
}

ResponsePtr RejectionResponse(const Rejection& rejection) {
  auto response = std::make_shared<v1::TrackResponse>();
  wire::RejectionToProto(RequestKindName(rejection.request), rejection.sequence, rejection.reason, rejection.status,
                         response->mutable_rejected());
  return response;
}

}  // namespace localizer::server
