// localizer-cli with the array file's "session" object (issue 19, clients/io/session_file.h) on
// a simulated scene (simulate tetra-water, 4 s, seed 1):
//   - `track` with the settings in the file writes row for row the estimates it writes with
//     the same settings as flags, and they differ from the defaults' (the settings arrive);
//   - a flag given wins over the file: file + --particles 2048 is flags with --particles 2048;
//   - `doa` reads the file's frame_samples and hop_samples as --frame and --hop, and its
//     direction weightings as --no-diffuse-weighting and --signal-weighting;
//   - a bad session object stops the command (exit 1) with a message naming the file and key.
// "Row for row": every field of every row equal as text, except tdoa_ms and filter_ms (stage
// wall times); the runs are seeded, so this holds exactly.
#include <gtest/gtest.h>

#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "tests/clients/cli_shell.h"
#include "tests/clients/test_util.h"

namespace localizer::io {
namespace {

#ifdef LOCALIZER_CLI_BIN
int Shell(const std::string& command, const testing::TempDir& dir) {
  return testing::RunCliShell(LOCALIZER_CLI_BIN, command, dir);
}
using testing::ReadText;
using testing::RowsWithoutTimes;

// The simulated array.json with `session` added, written to `path`.
void WriteSessionFile(const testing::TempDir& dir, const std::string& session, const std::string& path) {
  nlohmann::json array = nlohmann::json::parse(ReadText(dir.File("sim/array.json")));
  array["session"] = nlohmann::json::parse(session);
  std::ofstream(path) << array.dump(2);
}

class CliSessionFile : public ::testing::Test {
 protected:
  void SetUp() override {
    ASSERT_EQ(Shell("\"$CLI\" simulate --scenario tetra-water --duration 4 --seed 1 --out " + dir_.File("sim"), dir_),
              0)
        << ReadText(dir_.File("stderr.txt"));
  }
  // `track` on the simulated WAV with `array` and the extra flags, to `out`.
  void Track(const std::string& array, const std::string& flags, const std::string& out) {
    ASSERT_EQ(Shell("\"$CLI\" track --array " + array + " --wav " + dir_.File("sim/signals.wav") +
                        " --print-every 0 --out " + dir_.File(out) + " " + flags,
                    dir_),
              0)
        << ReadText(dir_.File("stderr.txt"));
  }
  testing::TempDir dir_;
};

constexpr const char* kSession = R"({"particles": 1024, "frame_samples": 2048, "hop_samples": 1024,
                                     "accel_noise_mps2": 0.5, "tdoa_sigma_s": 2.5e-05, "seed": 7})";
constexpr const char* kFlags =
    "--particles 1024 --frame 2048 --hop 1024 --accel-noise 0.5 --tdoa-sigma-us 25 "
    "--filter-seed 7";

TEST_F(CliSessionFile, TrackWithTheFileIsTrackWithTheFlags) {
  WriteSessionFile(dir_, kSession, dir_.File("session.json"));
  Track(dir_.File("sim/array.json"), kFlags, "flags.csv");
  Track(dir_.File("session.json"), "", "file.csv");
  Track(dir_.File("sim/array.json"), "", "defaults.csv");
  const auto from_flags = RowsWithoutTimes(dir_.File("flags.csv"));
  ASSERT_GT(from_flags.size(), 30u);
  EXPECT_EQ(RowsWithoutTimes(dir_.File("file.csv")), from_flags);
  EXPECT_NE(RowsWithoutTimes(dir_.File("defaults.csv")), from_flags) << "the settings must reach the session";
}

TEST_F(CliSessionFile, AFlagGivenWinsOverTheFile) {
  WriteSessionFile(dir_, kSession, dir_.File("session.json"));
  Track(dir_.File("session.json"), "--particles 2048 --filter-seed 3", "file.csv");
  Track(dir_.File("sim/array.json"),
        "--particles 2048 --frame 2048 --hop 1024 --accel-noise 0.5 --tdoa-sigma-us 25 --filter-seed 3", "flags.csv");
  EXPECT_EQ(RowsWithoutTimes(dir_.File("file.csv")), RowsWithoutTimes(dir_.File("flags.csv")));
}

TEST_F(CliSessionFile, DoaReadsTheFramingFromTheFile) {
  WriteSessionFile(dir_, R"({"frame_samples": 1024, "hop_samples": 512, "filter": "ekf"})", dir_.File("session.json"));
  const std::string doa = "\"$CLI\" doa --wav " + dir_.File("sim/signals.wav") + " --array ";
  ASSERT_EQ(Shell(doa + dir_.File("session.json") + " --out " + dir_.File("file.csv"), dir_), 0)
      << ReadText(dir_.File("stderr.txt"));
  ASSERT_EQ(Shell(doa + dir_.File("sim/array.json") + " --frame 1024 --hop 512 --out " + dir_.File("flags.csv"), dir_),
            0)
      << ReadText(dir_.File("stderr.txt"));
  ASSERT_EQ(Shell(doa + dir_.File("sim/array.json") + " --out " + dir_.File("defaults.csv"), dir_), 0);
  EXPECT_EQ(ReadText(dir_.File("file.csv")), ReadText(dir_.File("flags.csv")));
  EXPECT_NE(ReadText(dir_.File("defaults.csv")), ReadText(dir_.File("flags.csv")));
}

TEST_F(CliSessionFile, DoaReadsTheDirectionWeightingsFromTheFile) {
  WriteSessionFile(dir_, R"({"direction_diffuse_weighting": false, "direction_signal_weighting": false})",
                   dir_.File("session.json"));
  const std::string doa = "\"$CLI\" doa --wav " + dir_.File("sim/signals.wav") + " --array ";
  ASSERT_EQ(Shell(doa + dir_.File("session.json") + " --out " + dir_.File("file.csv"), dir_), 0)
      << ReadText(dir_.File("stderr.txt"));
  ASSERT_EQ(Shell(doa + dir_.File("sim/array.json") + " --no-diffuse-weighting --signal-weighting off --out " +
                      dir_.File("flags.csv"),
                  dir_),
            0)
      << ReadText(dir_.File("stderr.txt"));
  ASSERT_EQ(Shell(doa + dir_.File("sim/array.json") + " --out " + dir_.File("defaults.csv"), dir_), 0);
  EXPECT_EQ(ReadText(dir_.File("file.csv")), ReadText(dir_.File("flags.csv")));
  EXPECT_NE(ReadText(dir_.File("defaults.csv")), ReadText(dir_.File("flags.csv")));
  // A flag given wins over the file: the file's "off" with --signal-weighting on.
  ASSERT_EQ(Shell(doa + dir_.File("session.json") + " --signal-weighting on --out " + dir_.File("on.csv"), dir_), 0);
  ASSERT_EQ(Shell(doa + dir_.File("sim/array.json") + " --no-diffuse-weighting --signal-weighting on --out " +
                      dir_.File("on_flags.csv"),
                  dir_),
            0);
  EXPECT_EQ(ReadText(dir_.File("on.csv")), ReadText(dir_.File("on_flags.csv")));
}

TEST_F(CliSessionFile, ABadSessionObjectNamesTheFileAndTheKey) {
  const std::string track = "\"$CLI\" track --wav " + dir_.File("sim/signals.wav") + " --out " + dir_.File("out.csv") +
                            " --print-every 0 --array ";
  WriteSessionFile(dir_, R"({"particle": 1024})", dir_.File("unknown.json"));
  EXPECT_EQ(Shell(track + dir_.File("unknown.json"), dir_), 1);
  EXPECT_NE(ReadText(dir_.File("stderr.txt")).find(dir_.File("unknown.json") + ": session: unknown key \"particle\""),
            std::string::npos)
      << ReadText(dir_.File("stderr.txt"));
  WriteSessionFile(dir_, R"({"likelihood": "exact"})", dir_.File("bad.json"));
  EXPECT_EQ(Shell(track + dir_.File("bad.json"), dir_), 1);
  EXPECT_NE(ReadText(dir_.File("stderr.txt")).find(dir_.File("bad.json") + ": session.likelihood 'exact'"),
            std::string::npos)
      << ReadText(dir_.File("stderr.txt"));
}
#else
TEST(CliSessionFile, NeedsTheCli) { GTEST_SKIP() << "built without LOCALIZER_CLI_BIN"; }
#endif

}  // namespace
}  // namespace localizer::io
