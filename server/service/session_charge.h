// What admission charges a session against --memory-budget-mib (memory_budget.h).
//
// A session holds two kinds of memory for its whole life: its engine state (particles,
// frames, FFT plans, tracks: engine/pipeline/session_memory.h), and, for an audio session,
// the server's copy of the estimates it has written so that a resumed stream can be replayed
// (outbox.h: Outbox::kHistoryEstimates written responses, plus the EstimatePool's spares).
// For a 4-sensor array at 1024 particles that is ~260 KiB of history beside ~3.0 MiB of
// engine state (tests/server/admission_test.cc prints both); before it was charged, admission
// undercounted 300 such sessions by ~80 MiB. Detection sessions keep no estimate history
// (their responses are scans' tracks).
//
// An estimate's size is measured, not guessed: one response of the session's shape is built
// fully populated (a delay and a quality for every pair; max_sources sources with positions
// where its estimates list sources, engine::ReportsSources; the model probabilities of a multiple-model filter;
// a moving array's pose) and asked for its heap (SpaceUsedLong), plus an allowance for the
// shared pointer and the history's slot. The test holds it between every estimate a session
// sends and twice the largest.
#pragma once

#include <cstdint>

#include "engine/pipeline/session_config.h"

namespace localizer::server {

// Heap of one estimate response of `config`'s shape, fully populated, with its holder.
int64_t EstimateResponseBytes(const engine::AudioSessionConfig& config);

// The session's engine memory plus, for audio sessions, its resume history at capacity.
int64_t SessionChargeBytes(const engine::SessionConfig& config);

}  // namespace localizer::server
