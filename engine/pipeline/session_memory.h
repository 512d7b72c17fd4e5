// What a session will hold in memory, from its config alone: the server charges it against
// its memory budget before building the session (server/service/memory_budget.h), so that a
// config too large for what is left is refused without allocating it.
//
// An upper bound on the heap a session holds once running (its engine state: particles and
// their work arrays, each channel's frame and spectrum, each pair's cross-spectrum and GCC,
// FFT plans, the acquisition search, the detection tracker's tracks and per-scan work
// arrays; direction sessions: every sensor pair's cross-spectra, current and the earlier frames
// their rises look back on), not counting the blocks queued for it. The coefficients were measured
// (tests/pipeline/session_memory_test.cc checks the bound holds, and is not loose by more
// than its stated factor, over a spread of configs).
#pragma once

#include <cstdint>

#include "engine/pipeline/session_config.h"

namespace localizer::engine {

int64_t SessionMemoryBytes(const AudioSessionConfig& config);
int64_t SessionMemoryBytes(const DetectionSessionConfig& config);
int64_t SessionMemoryBytes(const SessionConfig& config);
// One Locate call on a block of `samples_per_channel` samples: the block, and the one frame
// as long as the block through the GCC.
int64_t LocateMemoryBytes(const AudioSessionConfig& config, int64_t samples_per_channel);

}  // namespace localizer::engine
