// The runner of an audio session (session_runner.h): sample blocks (and a moving array's IMU
// batches) through the engine Session, one Estimate per frame.
//
//   DecodeBlock  wire::DecodeBlock against the array's channel count and the session's
//                max_block_samples; a bad block is refused with the decoder's reason
//   DecodeImu    a fixed array refuses IMU batches ("not_moving"); else wire::DecodeImuBatch
//   DecodeScan   refused: "not_detections"
//   Process      a block: its SequenceGap first (the engine skips the missing time), then
//                Session::Process, each estimate encoded with the server's queue and total
//                latencies, stage histograms, the live-view track; an IMU batch: AddImu
//                (ordering against the previous batch is the engine's check) and the origin
#pragma once

#include <memory>
#include <vector>

#include "engine/core/estimate.h"
#include "engine/pipeline/session.h"
#include "server/service/session_runner.h"

namespace localizer::server {

class AudioRunner final : public SessionRunner {
 public:
  AudioRunner(std::unique_ptr<engine::Session> session, ServiceMetrics* metrics);

  const RunnerInfo& info() const override { return info_; }
  const engine::AudioSessionConfig& config() const override { return session_->config(); }
  v1::SessionConfig EffectiveConfig(const std::string& label) const override;

  WorkItem DecodeBlock(const v1::SampleBlock& block, Clock::time_point received,
                       wire::DecodedBlock* scratch) const override;
  WorkItem DecodeImu(const v1::ImuBatch& batch, Clock::time_point received) const override;
  WorkItem DecodeScan(const v1::Scan& scan, Clock::time_point received) const override;

  void Process(WorkItem& item, Clock::time_point started, TrackHistory* track, std::vector<ResponsePtr>* out) override;

 private:
  void ProcessBlock(const BlockWork& block, Clock::time_point received, Clock::time_point started, TrackHistory* track,
                    std::vector<ResponsePtr>* out);
  void ProcessImu(const ImuWork& imu, std::vector<ResponsePtr>* out);

  const std::unique_ptr<engine::Session> session_;  // touched by Process only
  ServiceMetrics* const metrics_;
  const StageHistograms& stages_;  // of the session's backend
  const RunnerInfo info_;
  const wire::BlockLimits block_limits_;     // what DecodeBlock accepts
  std::vector<engine::Estimate> estimates_;  // Process's scratch
};

}  // namespace localizer::server
