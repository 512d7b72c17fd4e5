// The commands of localizer-cli and the conventions they share.
//
// Exit codes: 0 success; 1 a runtime error (a file missing or malformed, data the engine
// rejects, a server that is unreachable or refuses the call), reported with the file or
// field it concerns, server errors as "CODE: message" with the gRPC status code name
// ("localizer-cli track: UNAVAILABLE: failed to connect to all addresses ..."); 2 a usage
// error (unknown command or flag, a malformed or out-of-range flag value, a required flag
// missing).
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "engine/core/flags.h"
#include "engine/core/status.h"

namespace localizer::cli {

enum ExitCode : int { kExitOk = 0, kExitRuntimeError = 1, kExitUsage = 2 };

// Each takes the arguments after the command name and returns the exit code.
int RunSimulate(const std::vector<std::string>& args);
int RunTrack(const std::vector<std::string>& args);
int RunDoa(const std::vector<std::string>& args);  // cmd_doa.cc
int RunScore(const std::vector<std::string>& args);
int RunPlot(const std::vector<std::string>& args);  // cmd_plot.cc
int RunLocate(const std::vector<std::string>& args);
int RunList(const std::vector<std::string>& args);
int RunClose(const std::vector<std::string>& args);
int RunExperiment(const std::vector<std::string>& args);
int RunAttitude(const std::vector<std::string>& args);       // cmd_attitude.cc
int RunAttitudeScore(const std::vector<std::string>& args);  // cmd_attitude.cc

// Parses `args` into `flags`. Returns an exit code when the command should stop now:
// 0 after printing --help to stdout, 2 after reporting a usage error on stderr.
std::optional<int> ParseFlagsOrExit(const std::string& command, FlagSet& flags, const std::vector<std::string>& args);
// "localizer-cli CMD: MESSAGE" on stderr plus a pointer to --help; returns 2.
int UsageError(const std::string& command, const std::string& message);
// "localizer-cli CMD: MESSAGE" on stderr; returns 1.
int RuntimeError(const std::string& command, const Status& status);
// "localizer-cli CMD: warning: MESSAGE" on stderr.
void Warning(const std::string& command, const std::string& message);

}  // namespace localizer::cli
