// What a load run prints: the progress line each second (stderr) and the result (JSON).
#pragma once

#include <nlohmann/json.hpp>
#include <string>

#include "clients/loadgen/latency_histogram.h"
#include "clients/loadgen/load_options.h"
#include "clients/loadgen/load_stats.h"

namespace localizer::loadgen {

// Facts of the run that the counters do not hold.
struct RunFacts {
  int connections = 0;
  double wall_s = 0.0;      // first session's start -> last session's end
  double cpu_user_s = 0.0;  // this process over the same span (getrusage)
  double cpu_system_s = 0.0;
  bool interrupted = false;  // stopped early by SIGINT / SIGTERM
};

// "[  12.0 s] live 300/300  blocks 35640  estimates 71210  p99 8.1 ms (last s) 9.0 ms (all)
//  late 0  rejected 0  errors 0"
std::string ProgressLine(double elapsed_s, const LoadOptions& options, const LoadStats& stats,
                         const LatencyCounts& last_second, const LatencyCounts& all);

// The result, every figure named with its unit:
//   sessions, sessions_started, sessions_opened, threads, connections, rate, encoding,
//   channels, sample_rate_hz, block_samples, frame_samples, hop_samples, particles, motion, backend,
//   backends {name: sessions}, duration_s, ramp_s, wall_s, interrupted,
//   blocks_sent, blocks_per_s (first send -> last send), estimates_received,
//   estimates_per_s (first send -> last estimate), estimates_unmatched,
//   estimates_initialised and estimates_source_present (the engine tracked the source),
//   latency_ms {p50, p95, p99, max, count} (null figures when no estimate arrived),
//   late_blocks, max_behind_schedule_ms, errors, errors_by_code {code: n}, rejected,
//   rejections {reason: n; "session_RESOURCE_EXHAUSTED": sessions refused}, gaps,
//   generator_cpu_s, generator_user_s, generator_system_s, generator_cores,
//   generator_cpu_us_per_block.
nlohmann::json ResultJson(const LoadOptions& options, const LoadStats& stats, const RunFacts& facts);

}  // namespace localizer::loadgen
