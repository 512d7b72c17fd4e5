#include "clients/cli/commands.h"

#include <iostream>

namespace localizer::cli {

std::optional<int> ParseFlagsOrExit(const std::string& command, FlagSet& flags, const std::vector<std::string>& args) {
  const Status status = flags.Parse(args);
  if (flags.help_requested()) {
    std::cout << flags.Usage();
    return kExitOk;
  }
  if (!status.ok()) return UsageError(command, status.message());
  return std::nullopt;
}

int UsageError(const std::string& command, const std::string& message) {
  std::cerr << "localizer-cli " << command << ": " << message << "\n"
            << "run 'localizer-cli " << command << " --help' for usage\n";
  return kExitUsage;
}

int RuntimeError(const std::string& command, const Status& status) {
  std::cerr << "localizer-cli " << command << ": " << status.message() << "\n";
  return kExitRuntimeError;
}

void Warning(const std::string& command, const std::string& message) {
  std::cerr << "localizer-cli " << command << ": warning: " << message << "\n";
}

}  // namespace localizer::cli
