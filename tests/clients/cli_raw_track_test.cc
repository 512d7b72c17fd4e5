// localizer-cli track --raw - (issue 19): a simulated scene (simulate tetra-water, 10 s, seed 1) piped through
// standard input as raw PCM gives the same estimates.csv as `track --wav` on the same
// samples, and bad raw input or flags get a clear error naming the flag and the exit code
// of commands.h.
//
// "The same": every field of every row equal as text, except tdoa_ms and filter_ms, which
// are stage wall times. This holds exactly (no tolerance) because the raw reader yields the
// WAV reader's floats bit for bit (tests/clients/raw_pcm_test.cc) and the runner and session
// are the same. The s16 comparison writes the same 16-bit codes once as a PCM_16 WAV and
// once raw; the f32 one pipes the simulator's float WAV samples as f32le.
#include <gtest/gtest.h>
#include <sndfile.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "clients/io/wav_io.h"
#include "tests/clients/cli_shell.h"
#include "tests/clients/test_util.h"

namespace localizer::io {
namespace {

using testing::TempDir;

#ifdef LOCALIZER_CLI_BIN
int Shell(const std::string& command, const testing::TempDir& dir) {
  return testing::RunCliShell(LOCALIZER_CLI_BIN, command, dir);
}
using testing::ReadText;
using testing::RowsWithoutTimes;

void ExpectSameEstimates(const std::string& wav_csv, const std::string& raw_csv) {
  const auto a = RowsWithoutTimes(wav_csv);
  const auto b = RowsWithoutTimes(raw_csv);
  // 10 s at 11025 Hz in 4096-sample frames every 2048: 52 frames, and the header.
  ASSERT_GE(a.size(), 50u) << "the WAV run wrote its estimates";
  ASSERT_EQ(a.size(), b.size());
  for (size_t r = 0; r < a.size(); ++r) ASSERT_EQ(a[r], b[r]) << "row " << r;
}

// Interleaved little-endian bytes.
void WriteRaw(const std::string& path, const std::string& bytes) {
  std::ofstream out(path, std::ios::binary);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

class CliRawTrack : public ::testing::Test {
 protected:
  void SetUp() override {
    ASSERT_EQ(Shell("\"$CLI\" simulate --scenario tetra-water --duration 10 --seed 1 --out " + dir_.File("sim"), dir_),
              0)
        << ReadText(dir_.File("stderr.txt"));
    auto wav = ReadWav(dir_.File("sim/signals.wav"));
    ASSERT_TRUE(wav.ok()) << wav.status().ToString();
    recording_ = std::move(*wav);
    ASSERT_EQ(recording_.channel_count, 4);
  }

  // track with the array of the scene, a fixed seed and `input` flags; returns the exit code.
  int Track(const std::string& input, const std::string& out_csv, const std::string& pipe_from = "") {
    const std::string track = "\"$CLI\" track --array " + dir_.File("sim/array.json") + " " + input + " --out " +
                              out_csv + " --filter-seed 7 --print-every 0";
    return Shell(pipe_from.empty() ? track : "cat " + pipe_from + " | " + track, dir_);
  }

  std::string Stderr() const { return ReadText(dir_.File("stderr.txt")); }
  std::string RateFlag() const {
    return " --sample-rate " + std::to_string(static_cast<int>(recording_.sample_rate_hz));
  }

  TempDir dir_;
  Recording recording_;
};

TEST_F(CliRawTrack, F32lePipedThroughStdinEqualsTheWavRun) {
  std::string bytes;
  for (int64_t n = 0; n < recording_.frames; ++n) {
    for (int c = 0; c < recording_.channel_count; ++c) {
      const uint32_t bits = std::bit_cast<uint32_t>(recording_.channel(c)[n]);
      for (int b = 0; b < 4; ++b) bytes.push_back(static_cast<char>(bits >> (8 * b)));
    }
  }
  WriteRaw(dir_.File("f32.raw"), bytes);
  ASSERT_EQ(Track("--wav " + dir_.File("sim/signals.wav"), dir_.File("wav.csv")), 0) << Stderr();
  ASSERT_EQ(Track("--raw - --raw-format f32le --channels 4" + RateFlag(), dir_.File("raw.csv"), dir_.File("f32.raw")),
            0)
      << Stderr();
  ExpectSameEstimates(dir_.File("wav.csv"), dir_.File("raw.csv"));
}

TEST_F(CliRawTrack, S16lePipedThroughStdinEqualsTheSameCodesAsA16BitWav) {
  // 16-bit codes of the scene (rounded, clipped to the code range), as a capture card gives.
  std::vector<int16_t> interleaved;
  for (int64_t n = 0; n < recording_.frames; ++n) {
    for (int c = 0; c < recording_.channel_count; ++c) {
      const double code = std::nearbyint(static_cast<double>(recording_.channel(c)[n]) * 32768.0);
      interleaved.push_back(static_cast<int16_t>(std::clamp(code, -32768.0, 32767.0)));
    }
  }
  SF_INFO info{};
  info.samplerate = static_cast<int>(recording_.sample_rate_hz);
  info.channels = recording_.channel_count;
  info.format = SF_FORMAT_WAV | SF_FORMAT_PCM_16;
  SNDFILE* file = sf_open(dir_.File("s16.wav").c_str(), SFM_WRITE, &info);
  ASSERT_NE(file, nullptr) << sf_strerror(nullptr);
  ASSERT_EQ(sf_writef_short(file, interleaved.data(), recording_.frames), recording_.frames);
  sf_close(file);
  std::string bytes;
  for (int16_t code : interleaved) {
    bytes.push_back(static_cast<char>(static_cast<uint16_t>(code) & 0xFF));
    bytes.push_back(static_cast<char>(static_cast<uint16_t>(code) >> 8));
  }
  WriteRaw(dir_.File("s16.raw"), bytes);

  ASSERT_EQ(Track("--wav " + dir_.File("s16.wav"), dir_.File("wav.csv")), 0) << Stderr();
  // --raw-format left out: s16le is the default.
  ASSERT_EQ(Track("--raw - --channels 4" + RateFlag(), dir_.File("raw.csv"), dir_.File("s16.raw")), 0) << Stderr();
  ExpectSameEstimates(dir_.File("wav.csv"), dir_.File("raw.csv"));
}

TEST_F(CliRawTrack, BadRawFlagsAreUsageErrorsNamingTheFlag) {
  const std::string raw = dir_.File("x.raw");
  WriteRaw(raw, std::string(4 * 2 * 100, '\0'));
  const std::string wav = " --wav " + dir_.File("sim/signals.wav");
  struct Case {
    std::string flags;
    std::string message;
  };
  const Case cases[] = {
      {"--raw " + raw + " --channels 4" + RateFlag() + wav, "--raw and --wav both given"},
      {"--raw " + raw + RateFlag(), "--raw needs --channels"},
      {"--raw " + raw + " --channels 4", "--raw needs --sample-rate"},
      {"--raw " + raw + " --channels 3" + RateFlag(), "--channels is 3 but"},
      {"--raw " + raw + " --channels 4 --raw-format s24le" + RateFlag(), "--raw-format: unknown raw PCM format"},
      {"--raw " + raw + " --channels 4 --sample-rate 0", "--sample-rate is 0, must be > 0"},
      {"--channels 4" + wav, "--channels needs --raw"},
      {"", "no recording: give --wav FILE or --raw FILE"},
  };
  for (const Case& c : cases) {
    EXPECT_EQ(Track(c.flags, dir_.File("out.csv")), 2) << c.flags;
    EXPECT_NE(Stderr().find(c.message), std::string::npos) << c.flags << "\n" << Stderr();
  }
}

TEST_F(CliRawTrack, BadRawDataIsARuntimeErrorNamingWhatIsWrong) {
  // 100 whole frames of silence and 3 bytes more, through a pipe: tracked, then refused.
  WriteRaw(dir_.File("partial.raw"), std::string(4 * 2 * 100 + 3, '\0'));
  EXPECT_EQ(Track("--raw - --channels 4" + RateFlag(), dir_.File("out.csv"), dir_.File("partial.raw")), 1);
  EXPECT_NE(Stderr().find("stdin (--raw -): 3 byte(s) left over"), std::string::npos) << Stderr();
  // The same as a file: refused before anything is read.
  EXPECT_EQ(Track("--raw " + dir_.File("partial.raw") + " --channels 4" + RateFlag(), dir_.File("out.csv")), 1);
  EXPECT_NE(Stderr().find("3 byte(s) left over"), std::string::npos) << Stderr();

  // A NaN in f32le: the session rejects the block, as it does a float WAV's.
  std::string bytes(4 * 4 * 5000, '\0');
  const uint32_t nan_bits = std::bit_cast<uint32_t>(std::nanf(""));
  for (int b = 0; b < 4; ++b) bytes[4 * 4 * 10 + 4 * 2 + b] = static_cast<char>(nan_bits >> (8 * b));  // frame 10, ch 2
  WriteRaw(dir_.File("nan.raw"), bytes);
  EXPECT_EQ(Track("--raw - --raw-format f32le --channels 4" + RateFlag(), dir_.File("out.csv"), dir_.File("nan.raw")),
            1);
  EXPECT_NE(Stderr().find("stdin (--raw -): block 1"), std::string::npos) << Stderr();
  EXPECT_NE(Stderr().find("not finite"), std::string::npos) << Stderr();
}
TEST_F(CliRawTrack, ARateOtherThanTheArrayFilesIsUsedWithAWarning) {
  WriteRaw(dir_.File("quiet.raw"), std::string(4 * 2 * 16000, '\0'));  // 1 s of silence at 16 kHz
  EXPECT_EQ(Track("--raw " + dir_.File("quiet.raw") + " --channels 4 --sample-rate 16000", dir_.File("out.csv")), 0)
      << Stderr();
  EXPECT_NE(Stderr().find("says sample_rate_hz 11025"), std::string::npos) << Stderr();
  EXPECT_NE(Stderr().find("Hz; using --sample-rate"), std::string::npos) << Stderr();
}
#else
TEST(CliRawTrack, NeedsTheCliBinary) { GTEST_SKIP() << "LOCALIZER_CLI_BIN not defined by the build"; }
#endif

}  // namespace
}  // namespace localizer::io
