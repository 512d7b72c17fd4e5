// localizer-loadgen: many concurrent Track sessions against a localizer-server from a few
// threads (gRPC's callback API), for measuring the server rather than the generator. The
// C++ twin of clients/python/loadtest.py, with its session parameters and defaults.
//
// Output: a progress line each second on stderr; the result as one JSON object on stdout
// (or in --json FILE), see load_report.h. Ctrl-C (SIGINT) or SIGTERM half-closes every
// stream and ends the run early, marked "interrupted"; a second one ends the process at once.
// Exit codes: 0 every session ended OK, nothing rejected and some estimates received;
// 1 otherwise (or a runtime error before the run: "CODE: message"); 2 usage error.
#include <csignal>
#include <fstream>
#include <iostream>
#include <string>
#include <vector>

#include "clients/loadgen/load_options.h"
#include "clients/loadgen/load_run.h"
#include "engine/core/flags.h"

namespace {

std::atomic<bool> g_stop{false};

void RequestStop(int) { g_stop.store(true); }

constexpr const char* kName = "localizer-loadgen";

int UsageError(const std::string& message) {
  std::cerr << kName << ": " << message << "\nrun '" << kName << " --help' for usage\n";
  return 2;
}

}  // namespace

int main(int argc, char** argv) {
  using namespace localizer;
  loadgen::LoadOptions options;
  FlagSet flags(std::string(kName) + " --target HOST:PORT --sessions N --duration S --rate realtime|max [flags]",
                "Load a localizer-server with N concurrent Track sessions streaming synthetic audio (a\n"
                "broadband source heard by a tetrahedron, as clients/python/loadtest.py sends), driven by\n"
                "a few threads through gRPC's callback API. Latency = block handed to gRPC -> each of its\n"
                "estimates received. Progress each second on stderr; the result as JSON on stdout (or\n"
                "--json FILE): blocks/s, latency_ms p50/p95/p99/max, errors, rejected, and the\n"
                "generator's own CPU per block. Exit 0 when every stream ended OK with nothing\n"
                "rejected, 1 otherwise, 2 on a usage error.");
  loadgen::RegisterLoadFlags(flags, &options);
  const Status parsed = flags.Parse(std::vector<std::string>(argv + 1, argv + argc));
  if (flags.help_requested()) {
    std::cout << flags.Usage();
    return 0;
  }
  if (!parsed.ok()) return UsageError(parsed.message());
  if (const Status valid = options.Validate(); !valid.ok()) return UsageError(valid.message());

  // The first signal asks for a graceful end; a second one (SA_RESETHAND) ends the process.
  struct sigaction action {};
  action.sa_handler = RequestStop;
  action.sa_flags = SA_RESETHAND;
  sigemptyset(&action.sa_mask);
  sigaction(SIGINT, &action, nullptr);
  sigaction(SIGTERM, &action, nullptr);

  auto result = loadgen::RunLoad(options, g_stop, [](const std::string& line) { std::cerr << line << std::endl; });
  if (!result.ok()) {
    std::cerr << kName << ": " << result.status().message() << "\n";
    return 1;
  }
  const nlohmann::json& r = *result;
  const std::string text = r.dump(2);
  if (options.json_path.empty()) {
    std::cout << text << std::endl;
  } else {
    std::ofstream out(options.json_path);
    out << text << "\n";
    if (!out) {
      std::cerr << kName << ": cannot write --json file \"" << options.json_path << "\"\n";
      return 1;
    }
  }
  std::cerr << kName << ": " << r["blocks_sent"] << " blocks, " << r["estimates_received"] << " estimates, p99 "
            << r["latency_ms"]["p99"] << " ms, " << r["errors"] << " errors, " << r["rejected"] << " rejected, "
            << r["generator_cpu_us_per_block"] << " us CPU per block\n";
  const bool failed =
      r["errors"].get<int64_t>() > 0 || r["rejected"].get<int64_t>() > 0 || r["estimates_received"].get<int64_t>() == 0;
  return failed ? 1 : 0;
}
