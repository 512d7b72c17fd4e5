// One load run: connect, start every session on its schedule, print progress each second,
// wait for every stream to end, and describe the run as JSON (load_report.h).
//
// Session i starts at t0 + spread x i / sessions (spread: --ramp, else one block period in
// realtime and 0 at max), uses connection i % connections and pacing thread i % threads.
// The generator's CPU (getrusage, every thread of the process) is taken over the run only:
// the synthetic recording is made before it.
#pragma once

#include <atomic>
#include <functional>
#include <nlohmann/json.hpp>
#include <string>

#include "clients/loadgen/load_options.h"
#include "engine/core/status.h"

namespace localizer::loadgen {

// `options` validated. `stop` may be raised at any time (a signal handler): sessions then
// half-close and the run ends early, marked interrupted. `progress` gets each second's line.
// Errors before the run (a credential file, no connection within 10 s): the Status, its
// message starting with the code name. Once the sessions run, the result comes back
// whatever happened to them.
StatusOr<nlohmann::json> RunLoad(const LoadOptions& options, const std::atomic<bool>& stop,
                                 const std::function<void(const std::string&)>& progress);

}  // namespace localizer::loadgen
