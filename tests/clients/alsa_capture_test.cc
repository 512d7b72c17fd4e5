// AlsaCaptureStream (clients/io/alsa_capture.h) without a sound card:
//  - ALSA's `file` plugin, defined in a configuration string, reads capture data from an
//    `infile` the test wrote (slaved to the `null` plugin, which is not real time): the
//    samples read equal the codes written, bit for bit, in s16, s32 and f32;
//  - an in-process ioplug device (alsa_fake_device.h), real time, one channel count, one
//    rate, S16_LE only: a mismatch is refused naming the device and what it offers; an
//    overrun is recovered, counted, and its loss estimated within a few frames of the truth
//    the device's counter shows; a device that delivers nothing ends with "no samples";
//  - a device that does not exist, and a stop request.
// Random codes come from std::mt19937 seeded per test.
#include "clients/io/alsa_capture.h"

#include <gtest/gtest.h>

#include <atomic>
#include <bit>
#include <chrono>
#include <cstdint>
#include <fstream>
#include <random>
#include <string>
#include <thread>
#include <tuple>
#include <vector>

#include "tests/clients/alsa_fake_device.h"
#include "tests/clients/test_util.h"

namespace localizer::io {
namespace {

using testing::FakeAlsaDevice;
using testing::TempDir;

// A capture device "scene" reading `infile` through ALSA's file plugin, slaved to null.
std::string FilePluginConfig(const std::string& infile) {
  return "pcm.scene {\n"
         "  type file\n"
         "  slave.pcm { type null }\n"
         "  file \"/dev/null\"\n"  // the plugin also writes what it captured; nowhere
         "  infile \"" +
         infile +
         "\"\n"
         "  format \"raw\"\n"
         "}\n";
}

void WriteBytes(const std::string& path, const std::vector<unsigned char>& bytes) {
  std::ofstream out(path, std::ios::binary);
  out.write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
}

AlsaCaptureOptions SceneOptions(const std::string& infile, int channels, double rate_hz, int64_t frames) {
  AlsaCaptureOptions options;
  options.device = "scene";
  options.config_text = FilePluginConfig(infile);
  options.channel_count = channels;
  options.sample_rate_hz = rate_hz;
  options.duration_s = static_cast<double>(frames) / rate_hz;  // the file plugin has no end of its own
  return options;
}

// Reads the whole stream in blocks of `block` frames; channel-major per block, appended.
std::vector<std::vector<float>> ReadAll(AlsaCaptureStream& stream, int64_t block) {
  std::vector<std::vector<float>> channels(static_cast<size_t>(stream.channel_count()));
  std::vector<float> buffer;
  while (true) {
    auto n = stream.Read(block, &buffer);
    EXPECT_TRUE(n.ok()) << n.status().ToString();
    if (!n.ok() || *n == 0) break;
    for (int c = 0; c < stream.channel_count(); ++c) {
      channels[c].insert(channels[c].end(), buffer.begin() + c * *n, buffer.begin() + (c + 1) * *n);
    }
  }
  return channels;
}

TEST(AlsaCapture, FilePluginDeliversTheS16CodesWrittenBitForBit) {
  if (!AlsaCaptureAvailable()) GTEST_SKIP() << kAlsaUnavailableMessage;
  TempDir dir;
  constexpr int kChannels = 4;
  constexpr int64_t kFrames = 11025 + 123;  // not a whole number of blocks or periods
  std::mt19937 random(19);
  std::uniform_int_distribution<int> code(-32768, 32767);
  std::vector<int16_t> codes(kChannels * kFrames);
  for (int16_t& c : codes) c = static_cast<int16_t>(code(random));
  codes[0] = -32768;  // the ends of the range
  codes[1] = 32767;
  std::vector<unsigned char> bytes;
  for (int16_t c : codes) {
    bytes.push_back(static_cast<unsigned char>(static_cast<uint16_t>(c) & 0xFF));
    bytes.push_back(static_cast<unsigned char>(static_cast<uint16_t>(c) >> 8));
  }
  WriteBytes(dir.File("in.raw"), bytes);

  AlsaCaptureOptions options = SceneOptions(dir.File("in.raw"), kChannels, 11025, kFrames);
  options.format = AlsaSampleFormat::kS16;
  auto stream = AlsaCaptureStream::Open(options);
  ASSERT_TRUE(stream.ok()) << stream.status().ToString();
  EXPECT_EQ((*stream)->sample_format(), RawPcmFormat::kS16le);
  EXPECT_EQ((*stream)->Describe(), "ALSA device 'scene'");
  const auto channels = ReadAll(**stream, 2756);
  ASSERT_EQ(channels[0].size(), static_cast<size_t>(kFrames));
  for (int64_t n = 0; n < kFrames; ++n) {
    for (int c = 0; c < kChannels; ++c) {
      ASSERT_EQ(channels[c][n], static_cast<float>(codes[n * kChannels + c]) / 32768.0f)
          << "frame " << n << " ch " << c;
    }
  }
  EXPECT_EQ((*stream)->frames_read(), kFrames);
  EXPECT_EQ((*stream)->overrun_count(), 0);
  EXPECT_EQ((*stream)->frames_lost(), 0);
}

TEST(AlsaCapture, FilePluginDeliversS32AndF32AsTheRawReaderScalesThem) {
  if (!AlsaCaptureAvailable()) GTEST_SKIP() << kAlsaUnavailableMessage;
  TempDir dir;
  constexpr int kChannels = 3;
  constexpr int64_t kFrames = 4000;
  std::mt19937 random(32);
  std::vector<unsigned char> bytes(4 * kChannels * kFrames);
  for (unsigned char& b : bytes) b = static_cast<unsigned char>(random() & 0xFF);
  // f32: finite values only (random bits make NaNs); the s32 reading uses the same bytes.
  std::vector<unsigned char> f32_bytes = bytes;
  std::uniform_real_distribution<float> value(-2.0f, 2.0f);
  for (size_t i = 0; i < f32_bytes.size(); i += 4) {
    const uint32_t bits = std::bit_cast<uint32_t>(value(random));
    for (int b = 0; b < 4; ++b) f32_bytes[i + b] = static_cast<unsigned char>(bits >> (8 * b));
  }
  for (const auto& [format, raw, data] : {std::tuple{AlsaSampleFormat::kS32, RawPcmFormat::kS32le, bytes},
                                          std::tuple{AlsaSampleFormat::kF32, RawPcmFormat::kF32le, f32_bytes}}) {
    WriteBytes(dir.File("in.raw"), data);
    AlsaCaptureOptions options = SceneOptions(dir.File("in.raw"), kChannels, 48000, kFrames);
    options.format = format;
    auto stream = AlsaCaptureStream::Open(options);
    ASSERT_TRUE(stream.ok()) << stream.status().ToString();
    EXPECT_EQ((*stream)->sample_format(), raw);
    const auto channels = ReadAll(**stream, 1000);
    std::vector<float> expected(kChannels * kFrames);
    ConvertInterleavedPcm(raw, data.data(), kFrames, kChannels, expected.data());
    ASSERT_EQ(channels[0].size(), static_cast<size_t>(kFrames));
    for (int c = 0; c < kChannels; ++c) {
      for (int64_t n = 0; n < kFrames; ++n) {
        ASSERT_EQ(std::bit_cast<uint32_t>(channels[c][n]), std::bit_cast<uint32_t>(expected[c * kFrames + n]))
            << AlsaSampleFormatName(format) << " frame " << n << " ch " << c;
      }
    }
  }
}

TEST(AlsaCapture, BestFormatIsS32WhereTheDeviceOffersEveryFormat) {
  if (!AlsaCaptureAvailable()) GTEST_SKIP() << kAlsaUnavailableMessage;
  AlsaCaptureOptions options;
  options.device = "silence";
  options.config_text = "pcm.silence { type null }\n";
  options.channel_count = 2;
  options.sample_rate_hz = 16000;
  options.duration_s = 0.5;
  auto stream = AlsaCaptureStream::Open(options);
  ASSERT_TRUE(stream.ok()) << stream.status().ToString();
  EXPECT_EQ((*stream)->sample_format(), RawPcmFormat::kS32le);
  // The duration limit ends the stream at exactly 0.5 s of frames.
  int64_t total = 0;
  std::vector<float> buffer;
  for (auto n = (*stream)->Read(3000, &buffer); n.ok() && *n > 0; n = (*stream)->Read(3000, &buffer)) total += *n;
  EXPECT_EQ(total, 8000);
}

TEST(AlsaCapture, ADeviceThatDoesNotExistIsAClearError) {
  if (!AlsaCaptureAvailable()) GTEST_SKIP() << kAlsaUnavailableMessage;
  AlsaCaptureOptions options;
  options.device = "no_such_device";
  options.config_text = "pcm.silence { type null }\n";
  options.channel_count = 2;
  options.sample_rate_hz = 16000;
  auto stream = AlsaCaptureStream::Open(options);
  ASSERT_FALSE(stream.ok());
  EXPECT_EQ(stream.status().code(), StatusCode::kNotFound);
  EXPECT_NE(stream.status().message().find("ALSA device 'no_such_device': cannot open for capture: No such file"),
            std::string::npos)
      << stream.status().message();
  // The file plugin with an infile that is not there: the device's name, and ALSA's reason.
  options.device = "scene";
  options.config_text = FilePluginConfig("/nonexistent/in.raw");
  stream = AlsaCaptureStream::Open(options);
  ASSERT_FALSE(stream.ok());
  EXPECT_NE(stream.status().message().find("ALSA device 'scene': cannot open for capture"), std::string::npos)
      << stream.status().message();
  EXPECT_NE(stream.status().message().find("/nonexistent/in.raw"), std::string::npos) << stream.status().message();
  // A configuration ALSA cannot parse.
  options.config_text = "pcm.scene { type file";
  stream = AlsaCaptureStream::Open(options);
  ASSERT_FALSE(stream.ok());
  EXPECT_NE(stream.status().message().find("cannot parse the ALSA configuration"), std::string::npos)
      << stream.status().message();
}

TEST(AlsaCapture, AStopRequestEndsTheStreamCleanly) {
  if (!AlsaCaptureAvailable()) GTEST_SKIP() << kAlsaUnavailableMessage;
  std::atomic<bool> stop{false};
  AlsaCaptureOptions options;
  options.device = "silence";
  options.config_text = "pcm.silence { type null }\n";
  options.channel_count = 1;
  options.sample_rate_hz = 8000;
  options.stop = &stop;  // no duration: only the stop ends it
  auto stream = AlsaCaptureStream::Open(options);
  ASSERT_TRUE(stream.ok()) << stream.status().ToString();
  std::vector<float> buffer;
  auto n = (*stream)->Read(800, &buffer);
  ASSERT_TRUE(n.ok());
  EXPECT_EQ(*n, 800);
  for (float v : buffer) ASSERT_EQ(v, 0.0f);  // the null plugin captures silence
  stop = true;
  n = (*stream)->Read(800, &buffer);
  ASSERT_TRUE(n.ok()) << n.status().ToString();
  EXPECT_EQ(*n, 0);
}

// The fake device, adopted; `stalled`: it never delivers.
StatusOr<std::unique_ptr<AlsaCaptureStream>> OpenFake(FakeAlsaDevice* device, const AlsaCaptureOptions& options,
                                                      unsigned channels, unsigned rate_hz, bool stalled = false) {
  std::string error;
  snd_pcm_t* pcm = device->Open(channels, rate_hz, stalled, &error);
  if (pcm == nullptr) return Internal(error);
  return AlsaCaptureStream::Adopt(pcm, options);
}

AlsaCaptureOptions FakeOptions(int channels, double rate_hz) {
  AlsaCaptureOptions options;
  options.device = "fake";
  options.channel_count = channels;
  options.sample_rate_hz = rate_hz;
  return options;
}

TEST(AlsaCapture, ChannelCountRateAndFormatTheDeviceCannotGiveAreRefused) {
  if (!AlsaCaptureAvailable()) GTEST_SKIP() << kAlsaUnavailableMessage;
  {
    FakeAlsaDevice device;
    auto stream = OpenFake(&device, FakeOptions(4, 8000), 2, 8000);
    ASSERT_FALSE(stream.ok());
    EXPECT_EQ(stream.status().code(), StatusCode::kInvalidArgument);
    EXPECT_NE(stream.status().message().find("ALSA device 'fake': cannot capture 4 channels (it offers 2)"),
              std::string::npos)
        << stream.status().message();
  }
  {
    FakeAlsaDevice device;
    auto stream = OpenFake(&device, FakeOptions(2, 48000), 2, 8000);
    ASSERT_FALSE(stream.ok());
    EXPECT_NE(stream.status().message().find("ALSA device 'fake': cannot capture at exactly 48000 Hz (it offers "
                                             "8000 Hz with 2 channels); localizer does not resample"),
              std::string::npos)
        << stream.status().message();
  }
  {
    FakeAlsaDevice device;
    AlsaCaptureOptions options = FakeOptions(2, 8000);
    options.format = AlsaSampleFormat::kF32;
    auto stream = OpenFake(&device, options, 2, 8000);
    ASSERT_FALSE(stream.ok());
    EXPECT_NE(stream.status().message().find("ALSA device 'fake': cannot deliver FLOAT_LE samples (of those it "
                                             "offers S16_LE"),
              std::string::npos)
        << stream.status().message();
  }
  {
    FakeAlsaDevice device;  // and what it can give, it gives: best = its only format
    auto stream = OpenFake(&device, FakeOptions(2, 8000), 2, 8000);
    ASSERT_TRUE(stream.ok()) << stream.status().ToString();
    EXPECT_EQ((*stream)->sample_format(), RawPcmFormat::kS16le);
  }
}

TEST(AlsaCapture, AnOverrunIsRecoveredCountedAndItsLossMeasured) {
  if (!AlsaCaptureAvailable()) GTEST_SKIP() << kAlsaUnavailableMessage;
  constexpr double kRateHz = 8000;
  FakeAlsaDevice device;
  AlsaCaptureOptions options = FakeOptions(2, kRateHz);
  options.period_s = 0.005;
  options.buffer_s = 0.05;  // 400 frames: a 0.2 s stall overruns it
  auto opened = OpenFake(&device, options, 2, static_cast<unsigned>(kRateHz));
  ASSERT_TRUE(opened.ok()) << opened.status().ToString();
  AlsaCaptureStream& stream = **opened;
  std::vector<float> buffer;
  int64_t last_index = -1;
  // A block as delivered: its frames follow one another, and the first follows the last block's
  // last frame after exactly the gap reported.
  const auto read_block = [&](int64_t frames, int64_t* true_gap) {
    auto n = stream.Read(frames, &buffer);
    ASSERT_TRUE(n.ok()) << n.status().ToString();
    ASSERT_EQ(*n, frames);
    const int64_t first = FakeAlsaDevice::FrameIndexOf(buffer[0], buffer[frames]);
    *true_gap = last_index < 0 ? 0 : first - last_index - 1;
    for (int64_t k = 1; k < frames; ++k) {
      ASSERT_EQ(FakeAlsaDevice::FrameIndexOf(buffer[k], buffer[frames + k]), first + k) << "frame " << k;
    }
    last_index = first + frames - 1;
  };
  int64_t gap = 0;
  for (int i = 0; i < 4; ++i) {
    read_block(200, &gap);
    EXPECT_EQ(gap, 0);
    EXPECT_EQ(stream.frames_lost_before_last_read(), 0);
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(200));  // the tracker stalls: 1600 frames > 400
  read_block(200, &gap);
  EXPECT_EQ(device.overruns(), 1);
  EXPECT_EQ(stream.overrun_count(), 1);
  // About 0.2 s of frames, minus what the buffer still held; the estimate from the clock is
  // within a couple of milliseconds of what the device's counter says.
  EXPECT_GT(gap, 1000);
  EXPECT_NEAR(static_cast<double>(stream.frames_lost_before_last_read()), static_cast<double>(gap), 0.002 * kRateHz)
      << "true gap " << gap;
  ::testing::Test::RecordProperty("true_gap_frames", std::to_string(gap));  // --gtest_output=xml shows them
  ::testing::Test::RecordProperty("estimated_gap_frames", std::to_string(stream.frames_lost_before_last_read()));
  EXPECT_EQ(stream.frames_lost(), stream.frames_lost_before_last_read());
  read_block(200, &gap);  // and it goes on without loss
  EXPECT_EQ(gap, 0);
  EXPECT_EQ(stream.frames_lost_before_last_read(), 0);
}

TEST(AlsaCapture, ADeviceThatDeliversNothingEndsWithATimeout) {
  if (!AlsaCaptureAvailable()) GTEST_SKIP() << kAlsaUnavailableMessage;
  FakeAlsaDevice device;
  AlsaCaptureOptions options = FakeOptions(2, 8000);
  options.no_data_timeout_s = 0.3;
  auto stream = OpenFake(&device, options, 2, 8000, /*stalled=*/true);
  ASSERT_TRUE(stream.ok()) << stream.status().ToString();
  std::vector<float> buffer;
  const auto start = std::chrono::steady_clock::now();
  auto n = (*stream)->Read(800, &buffer);
  const double waited_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  ASSERT_FALSE(n.ok());
  EXPECT_EQ(n.status().code(), StatusCode::kUnavailable);
  EXPECT_NE(n.status().message().find("ALSA device 'fake': no samples from the device for 0.3"), std::string::npos)
      << n.status().message();
  EXPECT_GE(waited_s, 0.3);
  EXPECT_LT(waited_s, 2.0);
}

TEST(AlsaCapture, BadOptionsNameTheField) {
  AlsaCaptureOptions options;
  options.device = "x";
  options.channel_count = 2;
  options.sample_rate_hz = 44100.5;
  EXPECT_NE(options.Validate().message().find("sample_rate_hz is 44100.5"), std::string::npos)
      << options.Validate().message();
  options.sample_rate_hz = 44100;
  options.buffer_s = 0.01;
  EXPECT_NE(options.Validate().message().find("buffer_s"), std::string::npos);
  EXPECT_FALSE(ParseAlsaSampleFormat("s24").ok());
  EXPECT_EQ(*ParseAlsaSampleFormat("f32"), AlsaSampleFormat::kF32);
}

}  // namespace
}  // namespace localizer::io
