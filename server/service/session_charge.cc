#include "server/service/session_charge.h"

#include <algorithm>
#include <memory>
#include <variant>

#include "engine/pipeline/session.h"
#include "engine/pipeline/session_memory.h"
#include "server/service/outbox.h"
#include "wire/estimate_wire.h"

namespace localizer::server {
namespace {

// make_shared's control block beside the message, and the history deque's slot.
constexpr int64_t kHolderBytes = 64;
constexpr int kModelProbabilities = 4;  // the largest multiple-model set (imm's cv, ct-left, ct-right, ca)

}  // namespace

int64_t EstimateResponseBytes(const engine::AudioSessionConfig& config) {
  const size_t pairs = config.sensors_m.empty() ? 0 : config.sensors_m.size() - 1;
  engine::Estimate e;
  e.delay_s.assign(pairs, 1e-3);
  e.quality.assign(pairs, 1.0);
  const engine::FilterKind kind = config.tracker.kind;
  if (kind == engine::FilterKind::kMmpf || kind == engine::FilterKind::kImm) {
    for (int k = 0; k < kModelProbabilities; ++k) e.model_probabilities.push_back({"ct-right", 0.25});
  }
  if (config.array_in_body_frame) e.platform = engine::PlatformAttitude{};
  // Sources, where the session's estimates list them (they may carry positions); a config the
  // session will refuse is charged as if it did.
  const StatusOr<bool> reports_sources = engine::ReportsSources(config);
  if (!reports_sources.ok() || *reports_sources) {
    engine::SourceEstimate source;
    source.direction = engine::Vec3::UnitX();
    source.position_m = engine::Vec3::Zero();
    source.position_covariance_m2 = engine::Mat3::Identity();
    e.sources.assign(static_cast<size_t>(config.EffectiveMaxSources()), source);
  }
  v1::TrackResponse response;
  wire::EstimateToProto(e, config.reference_sensor, "cuda", response.mutable_estimate());
  return static_cast<int64_t>(response.SpaceUsedLong()) + kHolderBytes;  // SpaceUsedLong counts the message itself
}

int64_t SessionChargeBytes(const engine::SessionConfig& config) {
  const int64_t engine_bytes = engine::SessionMemoryBytes(config);
  const auto* audio = std::get_if<engine::AudioSessionConfig>(&config);
  if (audio == nullptr) return engine_bytes;
  const int64_t kept = static_cast<int64_t>(Outbox::kHistoryEstimates + EstimatePool::kCapacity);
  return engine_bytes + kept * EstimateResponseBytes(*audio);
}

}  // namespace localizer::server
