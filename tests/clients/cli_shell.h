// Running localizer-cli through a shell from a test: pipes and redirections as a user types
// them (tests built with LOCALIZER_CLI_BIN, the binary's path).
#pragma once

#include <sys/wait.h>

#include <fstream>
#include <sstream>
#include <string>

#include "tests/clients/test_util.h"
#include "tests/server/run_shell.h"

namespace localizer::io::testing {

// Runs `command` (a shell line in which the CLI is "$CLI") and returns its exit code (-1 if
// it did not exit); stdout goes to dir/stdout.txt, stderr to dir/stderr.txt.
inline int RunCliShell(const std::string& cli_bin, const std::string& command, const TempDir& dir) {
  const std::string line =
      "CLI='" + cli_bin + "'; " + command + " > " + dir.File("stdout.txt") + " 2> " + dir.File("stderr.txt");
  const int status = localizer::testing::RunShell(line);
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

inline std::string ReadText(const std::string& path) {
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

}  // namespace localizer::io::testing
