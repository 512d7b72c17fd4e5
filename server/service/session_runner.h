// What one kind of session does: the SessionHost (session_host.h) keeps the lifecycle,
// the lock, the stream and the worker turn; its runner decides what the session's requests
// become and what one work item produces.
//
//   kind        runner            takes                          answers with
//   samples     AudioRunner       SampleBlock, ImuBatch (moving  Estimate per frame,
//               (audio_runner.h)  arrays)                        SequenceGap before a jump
//   detections  DetectionRunner   Scan                           TrackList per scan
//               (detection_runner.h)
//
// Every runner answers every request kind: one it does not take becomes an in-band refusal
// (a block to a detection session: "not_samples"; a scan to an audio session:
// "not_detections"; an IMU batch to a fixed array: "not_moving"), so the stream goes on.
// MakeSessionRunner is the one place that asks which kind a config is. Adding a kind means
// adding a runner (and its case there), nothing in the host, the reactor or the registry.
//
// Threads: the Decode* methods run on gRPC threads, outside the host's lock, possibly
// concurrently with Process; they read only what is fixed at creation (the config and the
// limits derived from it). Process runs on the session's worker, one item at a time and in
// order (the host's `scheduled` flag), and is the only code that touches the engine session.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "engine/core/status.h"
#include "engine/pipeline/session.h"
#include "localizer/v1/localizer.pb.h"
#include "server/service/inbox.h"
#include "server/service/outbox.h"
#include "server/service/service_metrics.h"
#include "server/service/track_history.h"
#include "wire/block_wire.h"

namespace localizer::server {

// What a session tells about itself (SessionOpened, SessionInfo, GET /sessions); fixed at
// creation.
struct RunnerInfo {
  std::string kind;               // "samples" | "detections" (the sessions JSON's "kind")
  std::string filter_type;        // the sessions JSON's "filter_type": the tracker ("tws" for detections)
  std::string backend;            // where it runs: "cpu" | "gpu"
  int channel_count = 0;          // SessionInfo.channel_count: sensors per sample block (0: takes none)
  bool reports_presence = false;  // its estimates carry source presence (the sessions JSON's "presence")
  // Audio sessions (SessionOpened): the array's shape ("linear" | "planar" | "volumetric")
  // and what the estimates carry ("position" | "direction"); empty for detection sessions.
  std::string array_shape;
  std::string localization;
};

class SessionRunner {
 public:
  virtual ~SessionRunner() = default;

  virtual const RunnerInfo& info() const = 0;
  // An audio session's config as the engine holds it (fixed at creation); a detection
  // session's is the default one (no array): what the live view and /sessions read.
  virtual const engine::AudioSessionConfig& config() const = 0;
  // The config SessionOpened reports (wire/config_wire.h), with the backend chosen.
  virtual v1::SessionConfig EffectiveConfig(const std::string& label) const = 0;

  // Reader side: a request's block, IMU batch or scan -> a work item for the inbox (or its
  // refusal), by the Decode* of its kind below. `scratch` is the stream's block decoding
  // buffer (its samples move into a BlockWork). A request holding none of the three (the
  // reactor never offers one) is refused as a block: "bad_request".
  WorkItem Decode(const v1::TrackRequest& request, Clock::time_point received, wire::DecodedBlock* scratch) const;
  virtual WorkItem DecodeBlock(const v1::SampleBlock& block, Clock::time_point received,
                               wire::DecodedBlock* scratch) const = 0;
  virtual WorkItem DecodeImu(const v1::ImuBatch& batch, Clock::time_point received) const = 0;
  virtual WorkItem DecodeScan(const v1::Scan& scan, Clock::time_point received) const = 0;

  // Worker side: one item taken from the inbox (never a Rejection: the host answers those)
  // -> its responses in order, appended to `out`; `started` is when the worker took it.
  // `track` is the session's live-view history.
  virtual void Process(WorkItem& item, Clock::time_point started, TrackHistory* track,
                       std::vector<ResponsePtr>* out) = 0;

  // Estimate responses to fill again (outbox.h): the session host's outbox puts back what its
  // history lets go; a runner that answers with estimates takes them from here.
  EstimatePool& estimate_pool() { return estimate_pool_; }

 private:
  EstimatePool estimate_pool_;
};

// The runner for `config`'s kind (FFT plans, particles: the engine session is built here).
// Errors are the engine's (INVALID_ARGUMENT naming the field, FAILED_PRECONDITION for a GPU
// backend without a device, ...). `metrics` must outlive the runner.
StatusOr<std::unique_ptr<SessionRunner>> MakeSessionRunner(const engine::SessionConfig& config,
                                                           ServiceMetrics* metrics);

// The BlockRejected answering `rejection`, as a response of its own.
ResponsePtr RejectionResponse(const Rejection& rejection);

}  // namespace localizer::server
