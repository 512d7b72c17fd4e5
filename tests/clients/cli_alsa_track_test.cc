// localizer-cli track --alsa (issue 19, "Audio in"), without a sound card: ALSA's `file`
// plugin, defined in an ALSA configuration the test writes (ALSA_CONFIG_PATH), serves a
// simulated scene (simulate tetra-water, 5 s, seed 1, as 16-bit codes) as a capture device;
// `track --alsa` on it gives the same estimates as `track --raw` on the same codes (every
// field of every row equal as text but the stage wall times), and the summary says what was
// captured and lost. The `null` plugin (silence, faster than real time) stands for a device
// without end: SIGINT ends the run cleanly. Bad flags are usage errors naming the flag.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "clients/io/alsa_capture.h"
#include "clients/io/wav_io.h"
#include "tests/clients/cli_shell.h"
#include "tests/clients/test_util.h"

namespace localizer::io {
namespace {

using testing::ReadText;
using testing::RowsWithoutTimes;
using testing::TempDir;

#ifdef LOCALIZER_CLI_BIN
int Shell(const std::string& command, const TempDir& dir) {
  return testing::RunCliShell(LOCALIZER_CLI_BIN, command, dir);
}

class CliAlsaTrack : public ::testing::Test {
 protected:
  static constexpr double kSceneS = 5.0;

  void SetUp() override {
    ASSERT_EQ(Shell("\"$CLI\" simulate --scenario tetra-water --duration 5 --seed 1 --out " + dir_.File("sim"), dir_),
              0)
        << Stderr();
    auto wav = ReadWav(dir_.File("sim/signals.wav"));
    ASSERT_TRUE(wav.ok()) << wav.status().ToString();
    recording_ = std::move(*wav);
    ASSERT_EQ(recording_.channel_count, 4);
    // 16-bit codes of the scene (rounded, clipped), interleaved little-endian, as a card gives them.
    std::ofstream raw(dir_.File("scene.raw"), std::ios::binary);
    for (int64_t n = 0; n < recording_.frames; ++n) {
      for (int c = 0; c < recording_.channel_count; ++c) {
        const double code = std::clamp(std::nearbyint(double{recording_.channel(c)[n]} * 32768.0), -32768.0, 32767.0);
        const auto bits = static_cast<uint16_t>(static_cast<int16_t>(code));
        raw.put(static_cast<char>(bits & 0xFF));
        raw.put(static_cast<char>(bits >> 8));
      }
    }
    // The whole ALSA configuration of the CLI runs: two devices, no sound card.
    std::ofstream conf(dir_.File("asound.conf"));
    conf << "pcm.scene {\n  type file\n  slave.pcm { type null }\n  file \"/dev/null\"\n  infile \""
         << dir_.File("scene.raw") << "\"\n  format \"raw\"\n}\n"
         << "pcm.silence { type null }\n";
  }

  // track with the scene's array, a fixed filter seed and `input` flags, the CLI run by
  // `prefix` (a command such as timeout) if given; returns the exit code.
  int Track(const std::string& input, const std::string& out_csv, const std::string& prefix = "") {
    return Shell("ALSA_CONFIG_PATH=" + dir_.File("asound.conf") + " " + prefix + "\"$CLI\" track --array " +
                     dir_.File("sim/array.json") + " " + input + " --out " + out_csv +
                     " --filter-seed 7 --print-every 0",
                 dir_);
  }
  std::string Stdout() const { return ReadText(dir_.File("stdout.txt")); }
  std::string Stderr() const { return ReadText(dir_.File("stderr.txt")); }
  std::string RateFlag() const {
    return " --sample-rate " + std::to_string(static_cast<int>(recording_.sample_rate_hz));
  }

  TempDir dir_;
  Recording recording_;
};

TEST_F(CliAlsaTrack, CaptureFromAFilePluginEqualsTheRawRunOnTheSameCodes) {
  if (!AlsaCaptureAvailable()) GTEST_SKIP() << kAlsaUnavailableMessage;
  ASSERT_EQ(Track("--raw " + dir_.File("scene.raw") + " --channels 4" + RateFlag(), dir_.File("raw.csv")), 0)
      << Stderr();
  ASSERT_EQ(Track("--alsa scene --alsa-format s16 --channels 4 --duration 5" + RateFlag(), dir_.File("alsa.csv")), 0)
      << Stderr();
  EXPECT_NE(Stderr().find("ALSA device 'scene': capturing 4 channels at 11025 Hz, s16le"), std::string::npos)
      << Stderr();
  EXPECT_NE(Stdout().find("capture: frames=" + std::to_string(recording_.frames) +
                          " overruns=0 samples_lost=0 stopped_by=duration"),
            std::string::npos)
      << Stdout();
  const auto raw = RowsWithoutTimes(dir_.File("raw.csv"));
  const auto alsa = RowsWithoutTimes(dir_.File("alsa.csv"));
  // 5 s at 11025 Hz in 4096-sample frames every 2048: 25 frames, and the header.
  ASSERT_GE(raw.size(), 20u);
  ASSERT_EQ(raw.size(), alsa.size());
  for (size_t r = 0; r < raw.size(); ++r) ASSERT_EQ(raw[r], alsa[r]) << "row " << r;
}

TEST_F(CliAlsaTrack, SigintEndsALiveRunCleanly) {
  if (!AlsaCaptureAvailable()) GTEST_SKIP() << kAlsaUnavailableMessage;
  // No --duration: the null device never ends. SIGINT after 1 s; --preserve-status gives the
  // CLI's own exit code.
  ASSERT_EQ(
      Track("--alsa silence --channels 4" + RateFlag(), dir_.File("live.csv"), "timeout --preserve-status -s INT 1 "),
      0)
      << Stderr();
  EXPECT_NE(Stdout().find("stopped_by=SIGINT"), std::string::npos) << Stdout();
  EXPECT_NE(Stdout().find("samples_lost=0"), std::string::npos) << Stdout();
  // The estimates written so far are all there: a header and whole rows.
  const std::string csv = ReadText(dir_.File("live.csv"));
  ASSERT_FALSE(csv.empty());
  EXPECT_EQ(csv.back(), '\n');
  EXPECT_GT(std::count(csv.begin(), csv.end(), '\n'), 1);
}

TEST_F(CliAlsaTrack, DeviceErrorsAreRuntimeErrorsNamingTheDevice) {
  if (!AlsaCaptureAvailable()) GTEST_SKIP() << kAlsaUnavailableMessage;
  EXPECT_EQ(Track("--alsa no_such_device --channels 4" + RateFlag(), dir_.File("out.csv")), 1);
  EXPECT_NE(Stderr().find("ALSA device 'no_such_device': cannot open for capture: No such file or directory"),
            std::string::npos)
      << Stderr();
}

TEST_F(CliAlsaTrack, WithoutAlsaTheFlagSaysHowToGetIt) {
  if (AlsaCaptureAvailable()) GTEST_SKIP() << "built with ALSA";
  EXPECT_EQ(Track("--alsa default --channels 4" + RateFlag(), dir_.File("out.csv")), 1);
  EXPECT_NE(Stderr().find("built without ALSA (install libasound2-dev"), std::string::npos) << Stderr();
}

TEST_F(CliAlsaTrack, BadAlsaFlagsAreUsageErrorsNamingTheFlag) {
  const std::string alsa = "--alsa scene --channels 4" + RateFlag();
  struct Case {
    std::string flags;
    std::string message;
  };
  const Case cases[] = {
      {alsa + " --wav " + dir_.File("sim/signals.wav"), "--alsa and --wav both given"},
      {alsa + " --raw " + dir_.File("scene.raw"), "--raw and --alsa both given"},
      {"--alsa scene" + RateFlag(), "--alsa needs --channels"},
      {"--alsa scene --channels 4", "--alsa needs --sample-rate"},
      {"--alsa scene --channels 3" + RateFlag(), "--channels is 3 but"},
      {alsa + " --alsa-format s24", "--alsa-format: unknown ALSA sample format 's24'"},
      {"--alsa scene --channels 4 --sample-rate 11025.5", "--sample-rate is 11025.5"},
      {alsa + " --duration -1", "--duration is -1"},
      {alsa + " --alsa-buffer 0.01", "--alsa-buffer is 0.01"},
      {alsa + " --raw-format s16le", "--raw-format needs --raw"},
      {alsa + " --server 127.0.0.1:1", "--alsa tracks locally"},
      {"--raw " + dir_.File("scene.raw") + " --channels 4 --duration 2" + RateFlag(), "--duration needs --alsa"},
      {"", "or --alsa DEVICE"},
  };
  for (const Case& c : cases) {
    EXPECT_EQ(Track(c.flags, dir_.File("out.csv")), 2) << c.flags;
    EXPECT_NE(Stderr().find(c.message), std::string::npos) << c.flags << "\n" << Stderr();
  }
}
#else
TEST(CliAlsaTrack, NeedsTheCliBinary) { GTEST_SKIP() << "built without LOCALIZER_CLI_BIN"; }
#endif

}  // namespace
}  // namespace localizer::io
