// engine::Estimate <-> the wire Estimate.
#pragma once

#include <string>

#include "engine/core/estimate.h"
#include "localizer/v1/localizer.pb.h"

namespace localizer::wire {

// Fills everything the engine measured; latency.queue_s and latency.total_s are the
// server's to set. Pair k is (reference_sensor, the k-th other sensor): it names each
// pair's sensor (engine/array/array_geometry.h).
void EstimateToProto(const engine::Estimate& e, int reference_sensor, const std::string& backend, v1::Estimate* out);

// The inverse, for clients that write estimates.csv from a stream (fields the wire does
// not carry stay default).
engine::Estimate EstimateFromProto(const v1::Estimate& p);

}  // namespace localizer::wire
