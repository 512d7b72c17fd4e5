// LocateRequest -> what engine::Locate takes, and its LocateResult -> LocateResponse.
#pragma once

#include "engine/array/array_geometry.h"
#include "engine/core/status.h"
#include "engine/pipeline/locate.h"
#include "localizer/v1/localizer.pb.h"
#include "wire/block_wire.h"
#include "wire/config_wire.h"

namespace localizer::wire {

struct DecodedLocate {
  engine::AudioSessionConfig config;
  DecodedBlock block;  // block.view points into block.samples after a successful decode
};

// INVALID_ARGUMENT for a detection config ("config.detections: ..."; Locate measures one
// block of samples), else as AudioConfigFromProto and DecodeBlock (the block's limits come from
// the config: its sensor count and max_block_samples).
Status DecodeLocateRequest(const v1::LocateRequest& request, const ConfigPolicy& policy, DecodedLocate* out);

// Every pair's TDOA, quality and peak SNR (`array` names each pair's sensor), the fix with
// its 3x3 covariance (row-major) and residual when one was found, and the GCC stage's time.
void LocateResultToProto(const engine::LocateResult& result, const engine::ArrayGeometry& array,
                         v1::LocateResponse* out);

}  // namespace localizer::wire
