// The runner of a detection session (session_runner.h): scans of plots through the engine's
// ScanSession (track-while-scan), one TrackList per scan.
//
//   DecodeScan   wire::DecodeScan (every plot checked); a bad scan is refused ("scan")
//   DecodeBlock  refused: "not_samples"
//   DecodeImu    refused: "not_moving" (a detection session has no moving array)
//   Process      ScanSession::Process: the track list with the server's total latency, the
//                scan metrics, the live view's targets; a scan out of time order (the
//                engine's check) is refused in order ("scan")
#pragma once

#include <memory>
#include <vector>

#include "engine/pipeline/scan_session.h"
#include "server/service/session_runner.h"

namespace localizer::server {

class DetectionRunner final : public SessionRunner {
 public:
  DetectionRunner(std::unique_ptr<engine::ScanSession> scans, ServiceMetrics* metrics);

  const RunnerInfo& info() const override { return info_; }
  const engine::AudioSessionConfig& config() const override { return kNoAudio; }
  v1::SessionConfig EffectiveConfig(const std::string& label) const override;

  WorkItem DecodeBlock(const v1::SampleBlock& block, Clock::time_point received,
                       wire::DecodedBlock* scratch) const override;
  WorkItem DecodeImu(const v1::ImuBatch& batch, Clock::time_point received) const override;
  WorkItem DecodeScan(const v1::Scan& scan, Clock::time_point received) const override;

  void Process(WorkItem& item, Clock::time_point started, TrackHistory* track, std::vector<ResponsePtr>* out) override;

 private:
  static inline const engine::AudioSessionConfig kNoAudio{};
  const std::unique_ptr<engine::ScanSession> scans_;  // touched by Process only
  ServiceMetrics* const metrics_;
  const RunnerInfo info_;
};

}  // namespace localizer::server
