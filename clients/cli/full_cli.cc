#include "clients/cli/full_cli.h"

#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <iostream>
#include <mutex>

#include "clients/cli/commands.h"

namespace localizer::cli {
namespace {

constexpr const char* kFullCliName = "localizer-cli-full";

std::vector<char*>& Arguments() {
  static std::vector<char*> arguments;
  return arguments;
}

// Execs localizer-cli-full; returns (only when that fails) the reason, for the caller to report.
std::string TryExecFullCli() {
  const std::string path = FullCliPath();
  std::vector<char*> argv = Arguments();
  if (argv.empty()) argv.push_back(const_cast<char*>(kFullCliName));
  argv[0] = const_cast<char*>(path.c_str());
  argv.push_back(nullptr);
  std::fflush(stdout);
  std::fflush(stderr);
  std::cout.flush();
  std::cerr.flush();
  ::execv(path.c_str(), argv.data());
  return path + ": " + std::strerror(errno);
}

std::string ExecFailure(const std::string& why, const std::string& reason) {
  return why + " needs " + kFullCliName + ", which could not be started: " + reason;
}

// Consulted only for backend gpu or auto; see MakeFullCliGpuProvider.
class FullCliGpuProvider final : public engine::UnavailableBackendProvider {
 public:
  std::string UnavailableReason() const override {
    std::lock_guard<std::mutex> lock(mutex_);
    if (failure_.empty()) failure_ = ExecFailure("the GPU backend", TryExecFullCli());
    return failure_;
  }

 private:
  mutable std::mutex mutex_;
  mutable std::string failure_;  // GUARDED_BY(mutex_): why the exec failed; "" before trying
};

bool IsFlag(const std::string& arg, const char* name) {
  const std::string flag = std::string("--") + name;
  return arg == flag || arg.rfind(flag + "=", 0) == 0;
}

}  // namespace

void SetProcessArguments(int argc, char** argv) { Arguments().assign(argv, argv + argc); }

std::string NeedsFullCli(const std::string& command, const std::vector<std::string>& args) {
  if (command == "locate" || command == "list" || command == "close") return command;
  for (std::size_t i = 0; i < args.size(); ++i) {
    const std::string& arg = args[i];
    if (IsFlag(arg, "server")) return command + " --server";
    if (arg == "--backend") {
      if (i + 1 < args.size() && args[i + 1] != "cpu") return command + " --backend " + args[i + 1];
    } else if (IsFlag(arg, "backend") && arg != "--backend=cpu") {
      return command + " " + arg;
    }
  }
  return "";
}

std::string FullCliPath() {
  std::error_code error;
  const std::filesystem::path self = std::filesystem::read_symlink("/proc/self/exe", error);
  if (error) return kFullCliName;  // execv then fails with ENOENT unless it is in the cwd
  return (self.parent_path() / kFullCliName).string();
}

int ExecFullCli(const std::string& why) {
  const std::string failure = ExecFailure(why, TryExecFullCli());  // before printing anything
  std::cerr << "localizer-cli: " << failure << "\n";
  return kExitRuntimeError;
}

int RunInFullCli(const std::vector<std::string>&) { return ExecFullCli("this command"); }

std::shared_ptr<engine::BackendProvider> MakeFullCliGpuProvider() { return std::make_shared<FullCliGpuProvider>(); }

}  // namespace localizer::cli
