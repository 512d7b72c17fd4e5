// Running localizer-cli through a shell from a test: pipes and redirections as a user types
// them (tests built with LOCALIZER_CLI_BIN, the binary's path).
#pragma once

#include <sys/wait.h>

#include <fstream>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

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

// An estimates CSV's rows as fields, without the stage wall-time columns (tdoa_ms,
// filter_ms), so two runs on the same input compare equal.
inline std::vector<std::vector<std::string>> RowsWithoutTimes(const std::string& path) {
  std::ifstream in(path);
  std::vector<std::vector<std::string>> rows;
  std::vector<bool> keep;
  std::string line;
  while (std::getline(in, line)) {
    std::vector<std::string> fields;
    std::stringstream split(line);
    std::string field;
    while (std::getline(split, field, ',')) fields.push_back(field);
    if (keep.empty()) {
      for (const std::string& name : fields) keep.push_back(name != "tdoa_ms" && name != "filter_ms");
    }
    std::vector<std::string> kept;
    for (size_t i = 0; i < fields.size() && i < keep.size(); ++i) {
      if (keep[i]) kept.push_back(fields[i]);
    }
    rows.push_back(std::move(kept));
  }
  return rows;
}

}  // namespace localizer::io::testing
