#include "clients/loadgen/load_report.h"

#include <cmath>
#include <cstdio>

namespace localizer::loadgen {

namespace {

double Round3(double value) { return std::round(value * 1000.0) / 1000.0; }

std::string Ms(const LatencyCounts& counts, double q) {
  if (counts.count == 0) return "-";
  char text[32];
  std::snprintf(text, sizeof(text), "%.1f ms", 1e3 * counts.Quantile(q));
  return text;
}

nlohmann::json TallyJson(const Tally& tally) {
  nlohmann::json out = nlohmann::json::object();
  for (const auto& [name, count] : tally) out[name] = count;
  return out;
}

// Events per second between two steady-clock instants; null when the span is empty.
nlohmann::json PerSecond(int64_t count, int64_t from_ns, int64_t to_ns) {
  if (from_ns < 0 || to_ns <= from_ns) return nullptr;
  return std::round(100.0 * static_cast<double>(count) / (1e-9 * static_cast<double>(to_ns - from_ns))) / 100.0;
}

}  // namespace

std::string ProgressLine(double elapsed_s, const LoadOptions& options, const LoadStats& stats,
                         const LatencyCounts& last_second, const LatencyCounts& all) {
  char text[320];
  std::snprintf(text, sizeof(text),
                "[%7.1f s] live %lld/%d  blocks %lld  estimates %lld  p99 %s (last s) %s (all)  late %lld  "
                "rejected %lld  errors %lld",
                elapsed_s, static_cast<long long>(stats.live.load()), options.sessions,
                static_cast<long long>(stats.blocks_sent.load()), static_cast<long long>(stats.estimates.load()),
                Ms(last_second, 0.99).c_str(), Ms(all, 0.99).c_str(), static_cast<long long>(stats.late_blocks.load()),
                static_cast<long long>(LoadStats::Sum(stats.rejections())),
                static_cast<long long>(LoadStats::Sum(stats.errors())));
  return text;
}

nlohmann::json ResultJson(const LoadOptions& o, const LoadStats& stats, const RunFacts& facts) {
  const LatencyCounts latency = stats.latency.Snapshot();
  const int64_t blocks = stats.blocks_sent.load();
  const int64_t estimates = stats.estimates.load();
  const int64_t first_send = stats.first_send_ns.load();
  const double cpu_s = facts.cpu_user_s + facts.cpu_system_s;
  const Tally errors = stats.errors(), rejections = stats.rejections();

  nlohmann::json lat = {{"count", latency.count}};
  for (const auto& [name, q] : {std::pair<const char*, double>{"p50", 0.50}, {"p95", 0.95}, {"p99", 0.99}}) {
    lat[name] = latency.count ? nlohmann::json(Round3(1e3 * latency.Quantile(q))) : nlohmann::json(nullptr);
  }
  lat["max"] = latency.count ? nlohmann::json(Round3(1e3 * latency.max_s)) : nlohmann::json(nullptr);

  nlohmann::json r;
  r["generator"] = "localizer-loadgen";
  r["target"] = o.target;
  r["sessions"] = o.sessions;
  r["sessions_started"] = stats.started.load();
  r["sessions_opened"] = stats.opened.load();
  r["threads"] = o.threads;
  r["connections"] = facts.connections;
  r["rate"] = o.rate;
  r["encoding"] = o.encoding;
  r["channels"] = o.channels;
  r["sample_rate_hz"] = o.sample_rate_hz;
  r["block_samples"] = o.block_samples;
  r["frame_samples"] = o.frame_samples;
  r["hop_samples"] = o.hop_samples;
  r["particles"] = o.particles;
  r["motion"] = o.motion;
  r["backend"] = o.backend;
  r["backends"] = TallyJson(stats.backends());
  r["duration_s"] = o.duration_s;
  r["ramp_s"] = o.ramp_s;
  r["wall_s"] = Round3(facts.wall_s);
  r["interrupted"] = facts.interrupted;
  r["blocks_sent"] = blocks;
  r["blocks_per_s"] = PerSecond(blocks, first_send, stats.last_send_ns.load());
  r["estimates_received"] = estimates;
  r["estimates_per_s"] = PerSecond(estimates, first_send, stats.last_estimate_ns.load());
  r["estimates_unmatched"] = stats.unmatched.load();
  r["estimates_initialised"] = stats.initialised.load();
  r["estimates_source_present"] = stats.present.load();
  r["latency_ms"] = lat;
  r["late_blocks"] = stats.late_blocks.load();
  r["max_behind_schedule_ms"] = Round3(1e-6 * static_cast<double>(stats.behind_max_ns.load()));
  r["errors"] = LoadStats::Sum(errors);
  r["errors_by_code"] = TallyJson(errors);
  r["rejected"] = LoadStats::Sum(rejections);
  r["rejections"] = TallyJson(rejections);
  r["gaps"] = stats.gaps.load();
  r["generator_cpu_s"] = Round3(cpu_s);
  r["generator_user_s"] = Round3(facts.cpu_user_s);
  r["generator_system_s"] = Round3(facts.cpu_system_s);
  r["generator_cores"] = facts.wall_s > 0 ? Round3(cpu_s / facts.wall_s) : 0.0;
  r["generator_cpu_us_per_block"] =
      blocks > 0 ? nlohmann::json(Round3(1e6 * cpu_s / static_cast<double>(blocks))) : nlohmann::json(nullptr);
  return r;
}

}  // namespace localizer::loadgen
