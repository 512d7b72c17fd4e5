// The start-up contract of localizer-cli (clients/cli/full_cli.h): the offline commands load
// neither gRPC/protobuf/abseil nor the CUDA runtime and cuFFT (they were two thirds of an
// offline command's start-up CPU); a server, the GPU or an array file asking for the GPU
// hand the command to localizer-cli-full, which answers as the single binary did; and a
// missing localizer-cli-full is a clear error (exit 1), not a silent CPU run.
// What the process loads is read from the dynamic loader's own report (LD_DEBUG=files:
// one "file=NAME [ns]; needed by ..." or "dynamically loaded by ..." line per object, an
// exec'd image included, as LD_DEBUG stays in its environment).
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "tests/clients/cli_shell.h"
#include "tests/clients/test_util.h"

namespace localizer::io {
namespace {

#if defined(LOCALIZER_CLI_BIN) && defined(LOCALIZER_CLI_FULL_BIN)
using testing::ReadText;

int Shell(const std::string& command, const testing::TempDir& dir) {
  return testing::RunCliShell(LOCALIZER_CLI_BIN, command, dir);
}

// The shared objects the loader opened, as named in LD_DEBUG=files lines ("file=NAME [").
std::vector<std::string> LoadedObjects(const std::string& ld_debug) {
  std::vector<std::string> names;
  for (size_t at = ld_debug.find("file="); at != std::string::npos; at = ld_debug.find("file=", at + 1)) {
    const size_t end = ld_debug.find_first_of(" \t\n", at);
    names.push_back(ld_debug.substr(at + 5, end - at - 5));
  }
  return names;
}

// The first loaded object whose name contains one of `parts`, or "".
std::string FirstLoaded(const std::string& ld_debug, const std::vector<std::string>& parts) {
  for (const std::string& name : LoadedObjects(ld_debug)) {
    for (const std::string& part : parts) {
      if (name.find(part) != std::string::npos) return name;
    }
  }
  return "";
}

const std::vector<std::string> kServerAndGpuLibraries = {"libgrpc", "libprotobuf", "libabsl", "libcudart",
                                                         "libcufft", "libcurand", "libcuda.", "libssl"};

class CliStartup : public ::testing::Test {
 protected:
  void SetUp() override {
    ASSERT_EQ(Shell("\"$CLI\" simulate --scenario tetra-air --duration 0.2 --out " + dir_.File("sim"), dir_), 0)
        << ReadText(dir_.File("stderr.txt"));
  }
  std::string Track(const std::string& array, const std::string& extra, const std::string& out) const {
    return "\"$CLI\" track --array " + array + " --wav " + dir_.File("sim/signals.wav") + " --print-every 0 --out " +
           dir_.File(out) + " " + extra;
  }
  // The array file with a "session" object asking for `backend`.
  std::string ArrayWithBackend(const std::string& backend) const {
    std::string json = ReadText(dir_.File("sim/array.json"));
    const size_t brace = json.rfind('}');
    json.insert(brace, ", \"session\": {\"backend\": \"" + backend + "\"}");
    const std::string path = dir_.File("array_" + backend + ".json");
    std::ofstream(path) << json;
    return path;
  }
  testing::TempDir dir_;
};

TEST_F(CliStartup, OfflineCommandsLoadNoServerOrGpuLibraries) {
  for (const std::string& command :
       {std::string("\"$CLI\" --help"), Track(dir_.File("sim/array.json"), "", "est.csv"),
        "\"$CLI\" simulate --scenario tetra-water --duration 0.5 --out " + dir_.File("sim2"),
        "\"$CLI\" score --truth " + dir_.File("sim/truth.csv") + " --estimates " + dir_.File("est.csv"),
        Track(dir_.File("sim/array.json"), "--backend cpu", "est_cpu.csv")}) {
    ASSERT_EQ(Shell("LD_DEBUG=files " + command, dir_), 0) << command << "\n" << ReadText(dir_.File("stderr.txt"));
    const std::string loaded = ReadText(dir_.File("stderr.txt"));
    ASSERT_FALSE(LoadedObjects(loaded).empty()) << "no LD_DEBUG report: is this glibc?";
    EXPECT_EQ(FirstLoaded(loaded, kServerAndGpuLibraries), "") << command;
    EXPECT_EQ(FirstLoaded(loaded, {"localizer-cli-full"}), "") << command << " went through localizer-cli-full";
  }
  EXPECT_EQ(testing::RowsWithoutTimes(dir_.File("est.csv")), testing::RowsWithoutTimes(dir_.File("est_cpu.csv")));
}

// --server goes to localizer-cli-full (which loads gRPC); its answer is the full binary's.
TEST_F(CliStartup, ServerCommandsRunInTheFullCli) {
  const std::string list = "list --server 127.0.0.1:1";  // nothing listens on port 1
  ASSERT_EQ(Shell("LD_DEBUG=files \"$CLI\" " + list, dir_), 1);
  const std::string loaded = ReadText(dir_.File("stderr.txt"));
  EXPECT_NE(FirstLoaded(loaded, {"libgrpc"}), "") << "list --server did not reach localizer-cli-full";
  EXPECT_NE(loaded.find("localizer-cli list: UNAVAILABLE"), std::string::npos) << loaded;
  ASSERT_EQ(Shell("\"$CLI\" help locate", dir_), 0);
  EXPECT_NE(ReadText(dir_.File("stdout.txt")).find("usage: localizer-cli locate --server"), std::string::npos);
  ASSERT_EQ(Shell(Track(dir_.File("sim/array.json"), "--server=127.0.0.1:1", "remote.csv"), dir_), 1);
  EXPECT_NE(ReadText(dir_.File("stderr.txt")).find("localizer-cli track: UNAVAILABLE"), std::string::npos)
      << ReadText(dir_.File("stderr.txt"));
}

// --backend gpu|auto, and an array file asking for gpu|auto, answer exactly as
// localizer-cli-full does here (with a device: the GPU; without: gpu's error, auto on the CPU).
TEST_F(CliStartup, GpuRequestsAnswerAsTheFullCli) {
  struct Case {
    std::string array, flag;
  };
  const std::vector<Case> cases = {{dir_.File("sim/array.json"), "--backend gpu"},
                                   {dir_.File("sim/array.json"), "--backend=auto"},
                                   {ArrayWithBackend("gpu"), ""},
                                   {ArrayWithBackend("auto"), ""}};
  for (const Case& c : cases) {
    const int code = Shell("LD_DEBUG=files " + Track(c.array, c.flag, "gpu.csv"), dir_);
    const std::string loaded = ReadText(dir_.File("stderr.txt"));
    EXPECT_NE(FirstLoaded(loaded, {"libgrpc"}), "") << c.array << " " << c.flag << ": not handed to the full CLI";
    const int full_code =
        testing::RunCliShell(LOCALIZER_CLI_FULL_BIN, Track(c.array, c.flag, "gpu_full.csv"), dir_);
    EXPECT_EQ(code, full_code) << c.array << " " << c.flag;
    if (full_code != 0) {
      const std::string full_err = ReadText(dir_.File("stderr.txt"));
      EXPECT_NE(full_err.find("backend gpu requested but unavailable"), std::string::npos) << full_err;
      EXPECT_NE(loaded.find(full_err), std::string::npos) << "not the full CLI's error:\n" << loaded;
    } else {
      EXPECT_EQ(testing::RowsWithoutTimes(dir_.File("gpu.csv")), testing::RowsWithoutTimes(dir_.File("gpu_full.csv")));
    }
  }
}

TEST_F(CliStartup, MissingFullCliIsAClearError) {
  const std::string alone = dir_.File("alone");
  std::filesystem::create_directories(alone);
  std::filesystem::copy_file(LOCALIZER_CLI_BIN, alone + "/localizer-cli");
  const std::string cli = alone + "/localizer-cli";
  ASSERT_EQ(testing::RunCliShell(cli, "\"$CLI\" list --server 127.0.0.1:1", dir_), 1);
  EXPECT_NE(ReadText(dir_.File("stderr.txt")).find("needs localizer-cli-full, which could not be started: " + alone),
            std::string::npos)
      << ReadText(dir_.File("stderr.txt"));
  // The array file's gpu: a usage-time error naming the missing binary; auto: the CPU.
  ASSERT_EQ(testing::RunCliShell(cli, Track(ArrayWithBackend("gpu"), "", "x.csv"), dir_), 2);
  EXPECT_NE(ReadText(dir_.File("stderr.txt")).find("backend gpu requested but unavailable: the GPU backend needs "
                                                   "localizer-cli-full"),
            std::string::npos)
      << ReadText(dir_.File("stderr.txt"));
  EXPECT_EQ(testing::RunCliShell(cli, Track(ArrayWithBackend("auto"), "", "x.csv"), dir_), 0)
      << ReadText(dir_.File("stderr.txt"));
  // Offline commands do not need it.
  EXPECT_EQ(testing::RunCliShell(cli, Track(dir_.File("sim/array.json"), "", "x.csv"), dir_), 0)
      << ReadText(dir_.File("stderr.txt"));
}
#else
TEST(CliStartup, NeedsTheCli) { GTEST_SKIP() << "built without LOCALIZER_CLI_BIN / LOCALIZER_CLI_FULL_BIN"; }
#endif

}  // namespace
}  // namespace localizer::io
