// localizer-cli track's --filter-seed (issue 19: one meaning per flag name; in simulate
// --seed is the scene's): the old --seed still works, says it is deprecated, and gives the
// same estimates; both together are a usage error (exit 2).
#include <gtest/gtest.h>

#include <fstream>
#include <sstream>
#include <string>

#include "tests/clients/test_util.h"
#include "tests/clients/cli_shell.h"

namespace localizer::io {
namespace {

#ifdef LOCALIZER_CLI_BIN
int Shell(const std::string& command, const testing::TempDir& dir) {
  return testing::RunCliShell(LOCALIZER_CLI_BIN, command, dir);
}
using testing::ReadText;

// The CSV's x_m, y_m, z_m columns (2 to 4), row by row.
std::string Positions(const std::string& path) {
  std::ifstream in(path);
  std::string line, out;
  while (std::getline(in, line)) {
    std::stringstream fields(line);
    std::string field;
    for (int column = 0; column < 4 && std::getline(fields, field, ','); ++column) {
      if (column >= 1) out += field + ",";
    }
    out += "\n";
  }
  return out;
}

TEST(CliTrackFlags, FilterSeedAndItsDeprecatedOldName) {
  testing::TempDir dir;
  ASSERT_EQ(Shell("\"$CLI\" simulate --scenario tetra-water --duration 3 --seed 1 --out " + dir.File("sim"), dir), 0)
      << ReadText(dir.File("stderr.txt"));
  const std::string track = "\"$CLI\" track --array " + dir.File("sim/array.json") + " --wav " +
                            dir.File("sim/signals.wav") + " --print-every 0 ";
  ASSERT_EQ(Shell(track + "--filter-seed 7 --out " + dir.File("new.csv"), dir), 0) << ReadText(dir.File("stderr.txt"));
  EXPECT_EQ(ReadText(dir.File("stderr.txt")).find("deprecated"), std::string::npos);
  ASSERT_EQ(Shell(track + "--seed 7 --out " + dir.File("old.csv"), dir), 0) << ReadText(dir.File("stderr.txt"));
  EXPECT_NE(ReadText(dir.File("stderr.txt")).find("--seed is deprecated, use --filter-seed"), std::string::npos);
  EXPECT_EQ(Positions(dir.File("old.csv")), Positions(dir.File("new.csv")));
  ASSERT_EQ(Shell(track + "--filter-seed 8 --out " + dir.File("other.csv"), dir), 0);
  EXPECT_NE(Positions(dir.File("other.csv")), Positions(dir.File("new.csv"))) << "the seed must reach the filter";
  EXPECT_EQ(Shell(track + "--seed 7 --filter-seed 7 --out " + dir.File("both.csv"), dir), 2);
  EXPECT_NE(ReadText(dir.File("stderr.txt")).find("give one"), std::string::npos) << ReadText(dir.File("stderr.txt"));
}
#else
TEST(CliTrackFlags, NeedsTheCli) { GTEST_SKIP() << "built without LOCALIZER_CLI_BIN"; }
#endif

}  // namespace
}  // namespace localizer::io
