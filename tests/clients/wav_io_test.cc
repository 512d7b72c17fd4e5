#include "clients/io/wav_io.h"

#include <gtest/gtest.h>
#include <sndfile.h>

#include <cmath>
#include <cstdint>
#include <fstream>
#include <random>

#include "tests/clients/test_util.h"

namespace localizer::io {
namespace {

using testing::TempDir;

Recording Noise(int channels, int64_t frames, double rate_hz, uint32_t seed) {
  Recording r;
  r.sample_rate_hz = rate_hz;
  r.channel_count = channels;
  r.frames = frames;
  std::mt19937 rng(seed);
  std::normal_distribution<float> normal(0.0f, 0.3f);
  for (int64_t i = 0; i < channels * frames; ++i) r.samples.push_back(normal(rng));
  return r;
}

// Writes integer PCM codes (left-justified in int32, libsndfile's int convention) as a
// mono file of `format` (SF_FORMAT_PCM_16/24/32).
void WritePcm(const std::string& path, int format, int rate_hz, const std::vector<int>& codes32) {
  SF_INFO info{};
  info.samplerate = rate_hz;
  info.channels = 1;
  info.format = SF_FORMAT_WAV | format;
  SNDFILE* file = sf_open(path.c_str(), SFM_WRITE, &info);
  ASSERT_NE(file, nullptr) << sf_strerror(nullptr);
  ASSERT_EQ(sf_writef_int(file, codes32.data(), static_cast<sf_count_t>(codes32.size())),
            static_cast<sf_count_t>(codes32.size()));
  sf_close(file);
}

TEST(WavIo, FloatMultichannelRoundTripIsExact) {
  TempDir dir;
  const Recording written = Noise(4, 5000, 11025.0, 7);
  ASSERT_TRUE(WriteWavFloat(dir.File("a.wav"), written).ok());
  auto read = ReadWav(dir.File("a.wav"));
  ASSERT_TRUE(read.ok()) << read.status().ToString();
  EXPECT_EQ(read->sample_rate_hz, 11025.0);
  EXPECT_EQ(read->channel_count, 4);
  EXPECT_EQ(read->frames, 5000);
  EXPECT_EQ(read->samples, written.samples);  // float32 stored as float32: bit exact
}

// Every channel count reads back into its own channel: the counts the reader unrolls
// (1-4, 6, 8) and the ones it loops over (5, 7, 9, 16), with an odd frame count.
TEST(WavIo, EveryChannelCountDeinterleavesToItsChannel) {
  TempDir dir;
  for (int channels : {1, 2, 3, 4, 5, 6, 7, 8, 9, 16}) {
    const Recording written = Noise(channels, 1001, 8000.0, 11 + static_cast<uint32_t>(channels));
    ASSERT_TRUE(WriteWavFloat(dir.File("c.wav"), written).ok());
    auto read = ReadWav(dir.File("c.wav"));
    ASSERT_TRUE(read.ok()) << read.status().ToString();
    ASSERT_EQ(read->channel_count, channels);
    EXPECT_EQ(read->samples, written.samples) << channels << " channels";
  }
}

// Integer PCM reads as code / 2^(bits-1). Tolerance: 1 LSB of the format, but not below
// float32's own resolution near full scale (2^-24), which int32 codes exceed.
void ExpectPcmScaling(int format, int bits) {
  TempDir dir;
  const int shift = 32 - bits;
  const int64_t min_code = -(int64_t{1} << (bits - 1));
  const int64_t max_code = (int64_t{1} << (bits - 1)) - 1;
  std::vector<int64_t> codes = {min_code, max_code, 0, 1, -1, max_code / 3, min_code / 7};
  std::vector<int> codes32;
  for (int64_t c : codes) codes32.push_back(static_cast<int>(c * (int64_t{1} << shift)));
  WritePcm(dir.File("pcm.wav"), format, 32000, codes32);
  auto read = ReadWav(dir.File("pcm.wav"));
  ASSERT_TRUE(read.ok()) << read.status().ToString();
  ASSERT_EQ(read->frames, static_cast<int64_t>(codes.size()));
  const double full_scale = std::ldexp(1.0, bits - 1);
  const double tolerance = std::max(1.0 / full_scale, std::ldexp(1.0, -24));
  for (size_t i = 0; i < codes.size(); ++i) {
    EXPECT_NEAR(read->samples[i], static_cast<double>(codes[i]) / full_scale, tolerance)
        << bits << "-bit code " << codes[i];
  }
  EXPECT_EQ(read->samples[0], -1.0f) << "most negative code is exactly -full scale";
}

TEST(WavIo, Int16ScalesToFullScaleOne) { ExpectPcmScaling(SF_FORMAT_PCM_16, 16); }
TEST(WavIo, Int24ScalesToFullScaleOne) { ExpectPcmScaling(SF_FORMAT_PCM_24, 24); }
TEST(WavIo, Int32ScalesToFullScaleOne) { ExpectPcmScaling(SF_FORMAT_PCM_32, 32); }

TEST(WavIo, StreamChunksEqualTheWholeFile) {
  TempDir dir;
  const Recording written = Noise(3, 10007, 8000.0, 3);
  ASSERT_TRUE(WriteWavFloat(dir.File("s.wav"), written).ok());
  auto stream = WavStream::Open({dir.File("s.wav")});
  ASSERT_TRUE(stream.ok());
  std::vector<float> chunk;
  int64_t offset = 0;
  while (true) {
    auto n = stream->Read(1000, &chunk);
    ASSERT_TRUE(n.ok());
    if (*n == 0) break;
    ASSERT_EQ(chunk.size(), static_cast<size_t>(3 * *n));
    for (int c = 0; c < 3; ++c) {
      for (int64_t i = 0; i < *n; ++i) {
        ASSERT_EQ(chunk[c * *n + i], written.channel(c)[offset + i]);
      }
    }
    offset += *n;
  }
  EXPECT_EQ(offset, 10007);
  EXPECT_EQ(stream->frames_read(), 10007);
}

TEST(WavIo, MonoSetTruncatesToShortestWithWarning) {
  TempDir dir;
  const Recording a = Noise(1, 1000, 8000.0, 1);
  const Recording b = Noise(1, 990, 8000.0, 2);
  ASSERT_TRUE(WriteWavFloat(dir.File("a.wav"), a).ok());
  ASSERT_TRUE(WriteWavFloat(dir.File("b.wav"), b).ok());
  std::string warning;
  auto set = ReadWavSet({dir.File("a.wav"), dir.File("b.wav")}, &warning);
  ASSERT_TRUE(set.ok()) << set.status().ToString();
  EXPECT_EQ(set->channel_count, 2);
  EXPECT_EQ(set->frames, 990);
  EXPECT_NE(warning.find("truncated to 990"), std::string::npos) << warning;
  EXPECT_EQ(set->channel(0)[989], a.samples[989]);
  EXPECT_EQ(set->channel(1)[0], b.samples[0]);
}

TEST(WavIo, MonoSetRejectsMismatchedRatesLengthsAndChannels) {
  TempDir dir;
  ASSERT_TRUE(WriteWavFloat(dir.File("a.wav"), Noise(1, 9000, 8000.0, 1)).ok());
  ASSERT_TRUE(WriteWavFloat(dir.File("r.wav"), Noise(1, 9000, 16000.0, 1)).ok());
  ASSERT_TRUE(WriteWavFloat(dir.File("short.wav"), Noise(1, 500, 8000.0, 1)).ok());
  ASSERT_TRUE(WriteWavFloat(dir.File("stereo.wav"), Noise(2, 9000, 8000.0, 1)).ok());
  std::string warning;
  auto rates = ReadWavSet({dir.File("a.wav"), dir.File("r.wav")}, &warning);
  ASSERT_FALSE(rates.ok());
  EXPECT_NE(rates.status().message().find("16000"), std::string::npos);
  EXPECT_NE(rates.status().message().find("8000"), std::string::npos);
  EXPECT_NE(rates.status().message().find("r.wav"), std::string::npos);
  auto lengths = ReadWavSet({dir.File("a.wav"), dir.File("short.wav")}, &warning);
  ASSERT_FALSE(lengths.ok());  // 8500 frames = 1.06 s apart
  EXPECT_NE(lengths.status().message().find("not one recording"), std::string::npos);
  auto stereo = ReadWavSet({dir.File("a.wav"), dir.File("stereo.wav")}, &warning);
  ASSERT_FALSE(stereo.ok());
  EXPECT_NE(stereo.status().message().find("stereo.wav: has 2 channels"), std::string::npos);
}

TEST(WavIo, MissingAndBrokenFilesAreNamed) {
  TempDir dir;
  auto missing = ReadWav(dir.File("nope.wav"));
  ASSERT_FALSE(missing.ok());
  EXPECT_EQ(missing.status().code(), StatusCode::kNotFound);
  EXPECT_NE(missing.status().message().find("nope.wav"), std::string::npos);
  {
    std::ofstream junk(dir.File("junk.wav"));
    junk << "this is not a wav file";
  }
  auto junk = ReadWav(dir.File("junk.wav"));
  ASSERT_FALSE(junk.ok());
  EXPECT_NE(junk.status().message().find("junk.wav"), std::string::npos);
}

TEST(WavIo, WriteRejectsNonIntegerRate) {
  TempDir dir;
  EXPECT_FALSE(WriteWavFloat(dir.File("x.wav"), Noise(1, 10, 8000.5, 1)).ok());
}

}  // namespace
}  // namespace localizer::io
