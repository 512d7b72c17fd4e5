// localizer-cli: simulate a scenario to files, track a recording, score a track; or do the
// same through a localizer-server (--server), locate one block, list and close sessions.
// See commands.h for the exit codes; `localizer-cli CMD --help` for each command's flags.
// Compiled twice (full_cli.h): as localizer-cli-full, every command with gRPC and the GPU
// backend; with LOCALIZER_CLI_OFFLINE as localizer-cli, which runs the offline commands
// itself and execs localizer-cli-full for the others.
#include <iostream>
#include <string>
#include <vector>

#include "clients/cli/commands.h"
#include "engine/core/version.h"
#include "engine/pipeline/backend.h"
#ifdef LOCALIZER_CLI_OFFLINE
#include "clients/cli/full_cli.h"
#else
#include "gpu/backend/gpu_backend.h"
#endif

namespace localizer::cli {
namespace {

struct Command {
  const char* name;
  const char* summary;
  int (*run)(const std::vector<std::string>& args);
};

constexpr Command kCommands[] = {
    {"simulate",
     "simulate a named scenario to signals.wav, array.json and truth.csv\n"
     "            (--server: stream it live through a server session and score the track)",
     RunSimulate},
    {"track",
     "track a source in a multichannel WAV (or one mono WAV per sensor) to a CSV\n"
     "            (--server: on a server session, same CSV, plus latency percentiles)",
     RunTrack},
    {"doa",
     "directions of the sources in each frame of a recording, for arrays of any shape\n"
     "            (linear, planar, volumetric; SRP-PHAT) to a CSV",
     RunDoa},
    {"score", "compare an estimates CSV with a truth CSV (rmse, median, p95, max error)", RunScore},
    {"plot", "draw an estimates CSV against its truth and sensors as an SVG picture", RunPlot},
#ifdef LOCALIZER_CLI_OFFLINE
    {"locate", "one block of a recording through the server's one-shot Locate: pairs and fix", RunInFullCli},
    {"list", "the sessions a server holds, one line each", RunInFullCli},
    {"close", "end a server session (needs its resume token)", RunInFullCli},
#else
    {"locate", "one block of a recording through the server's one-shot Locate: pairs and fix", RunLocate},
    {"list", "the sessions a server holds, one line each", RunList},
    {"close", "end a server session (needs its resume token)", RunClose},
#endif
    {"experiment",
     "reproduce a reference experiment and print its table\n"
     "            (pf-vs-ekf-2d, fwl, tws)",
     RunExperiment},
    {"attitude", "orientation from an IMU CSV (gyro + accelerometer [+ magnetometer]) to a CSV", RunAttitude},
    {"attitude-score",
     "score an orientation CSV against the IMU CSV's motion-capture truth\n"
     "               (BROAD's total, heading and inclination RMSE, degrees)",
     RunAttitudeScore},
};

std::string GlobalUsage() {
  std::string text =
      "usage: localizer-cli COMMAND [flags]\n\n"
      "Acoustic source localisation from time differences of arrival (GCC-PHAT + particle\n"
      "filter), on files or through a localizer-server (gRPC).\n\ncommands:\n";
  for (const Command& c : kCommands) {
    std::string name = std::string("  ") + c.name;
    name.resize(name.size() < 11 ? 12 : name.size() + 1, ' ');  // at least one space
    text += name + c.summary + "\n";
  }
  text +=
      "\n'localizer-cli COMMAND --help' lists a command's flags, defaults and units;\n"
      "'localizer-cli --version' prints the version.\n"
      "Exit codes: 0 success, 1 runtime error (file, data or server: \"CODE: message\" with the\n"
      "gRPC status code), 2 usage error.\n"
      "Example:\n"
      "  localizer-cli simulate --scenario tetra-water --out run --duration 6\n"
      "  localizer-cli track --array run/array.json --wav run/signals.wav --out run/est.csv\n"
      "  localizer-cli score --truth run/truth.csv --estimates run/est.csv\n"
      "  localizer-cli plot --estimates run/est.csv --truth run/truth.csv --array run/array.json --out run/track.svg\n"
      "  localizer-cli doa --array board.json --wav talk.wav --out directions.csv\n"
      "  localizer-cli experiment pf-vs-ekf-2d --runs 100 --seed 1\n"
      "  localizer-cli attitude --imu trial.csv --out orientation.csv --mag\n"
      "  localizer-cli attitude-score --imu trial.csv --estimates orientation.csv\n"
      "With a server (localizer-server --listen 127.0.0.1:50051):\n"
      "  localizer-cli simulate --scenario tetra-water --duration 6 --server 127.0.0.1:50051\n"
      "  localizer-cli track --server 127.0.0.1:50051 --array run/array.json \\\n"
      "      --wav run/signals.wav --out run/est-server.csv\n"
      "  localizer-cli locate --server 127.0.0.1:50051 --array run/array.json \\\n"
      "      --wav run/signals.wav --start-s 2 --duration-s 0.5\n"
      "  localizer-cli list --server 127.0.0.1:50051\n";
  return text;
}

const Command* FindCommand(const std::string& name) {
  for (const Command& c : kCommands) {
    if (name == c.name) return &c;
  }
  return nullptr;
}

int UnknownCommand(const std::string& name) {
  std::cerr << "localizer-cli: unknown command \"" << name << "\"\n"
            << "run 'localizer-cli --help' for the list of commands\n";
  return kExitUsage;
}

int Main(int argc, char** argv) {
#ifdef LOCALIZER_CLI_OFFLINE
  SetProcessArguments(argc, argv);
#endif
  if (argc < 2) {
    std::cerr << GlobalUsage();
    return kExitUsage;
  }
  const std::string name = argv[1];
  if (name == "help" && argc > 2) {  // "help CMD" is "CMD --help"
    const Command* command = FindCommand(argv[2]);
    return command != nullptr ? command->run({"--help"}) : UnknownCommand(argv[2]);
  }
  if (name == "--help" || name == "-h" || name == "help") {
    std::cout << GlobalUsage();
    return kExitOk;
  }
  if (name == "--version" || name == "version") {
    std::cout << "localizer-cli " << kLocalizerVersion << "\n";
    return kExitOk;
  }
  const Command* command = FindCommand(name);
  if (command == nullptr) return UnknownCommand(name);
  std::vector<std::string> args(argv + 2, argv + argc);
#ifdef LOCALIZER_CLI_OFFLINE
  // A server or the GPU: localizer-cli-full runs the command (full_cli.h).
  if (const std::string why = NeedsFullCli(name, args); !why.empty()) return ExecFullCli(why);
  // A session that asks for the GPU anyway (an array file's backend) execs it then.
  engine::SetGpuProvider(MakeFullCliGpuProvider());
#else
  // Local sessions (--backend gpu|auto without --server) use the GPU when there is one.
  if (const Status gpu = gpu::RegisterGpuBackend(); !gpu.ok()) {
    std::cerr << "localizer-cli: " << gpu.message() << "\n";
    return kExitRuntimeError;
  }
#endif
  const int code = command->run(args);
  engine::SetGpuProvider(nullptr);  // stop the GPU dispatchers before static destruction
  return code;
}

}  // namespace
}  // namespace localizer::cli

int main(int argc, char** argv) { return localizer::cli::Main(argc, argv); }
