// clients/io/raw_pcm: each format gives the WAV reader's floats bit for bit (the same codes
// written once as a WAV file through libsndfile and once as raw bytes), blocks and lengths
// for files and pipes, the trailing partial frame, and bad options.
#include "clients/io/raw_pcm.h"

#include <fcntl.h>
#include <gtest/gtest.h>
#include <sndfile.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <limits>
#include <random>
#include <thread>
#include <type_traits>
#include <vector>

#include "clients/io/wav_io.h"
#include "tests/clients/test_util.h"

namespace localizer::io {
namespace {

using testing::TempDir;

constexpr int kChannels = 3;
constexpr int kRateHz = 16000;

// Little-endian bytes of interleaved samples, as arecord / sox / ffmpeg write them.
void AppendLe(uint32_t value, int bytes, std::string* out) {
  for (int b = 0; b < bytes; ++b) out->push_back(static_cast<char>((value >> (8 * b)) & 0xFF));
}

void WriteBytes(const std::string& path, const std::string& bytes) {
  std::ofstream out(path, std::ios::binary);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

// Writes interleaved `frames` to a WAV file of `format` without any conversion: shorts into
// PCM_16, ints into PCM_32 and floats into FLOAT are stored as given.
template <typename T>
void WriteWav(const std::string& path, int format, const std::vector<T>& interleaved) {
  SF_INFO info{};
  info.samplerate = kRateHz;
  info.channels = kChannels;
  info.format = SF_FORMAT_WAV | format;
  SNDFILE* file = sf_open(path.c_str(), SFM_WRITE, &info);
  ASSERT_NE(file, nullptr) << sf_strerror(nullptr);
  const sf_count_t frames = static_cast<sf_count_t>(interleaved.size() / kChannels);
  sf_count_t written = 0;
  if constexpr (std::is_same_v<T, int16_t>) written = sf_writef_short(file, interleaved.data(), frames);
  if constexpr (std::is_same_v<T, int32_t>) written = sf_writef_int(file, interleaved.data(), frames);
  if constexpr (std::is_same_v<T, float>) written = sf_writef_float(file, interleaved.data(), frames);
  ASSERT_EQ(written, frames);
  sf_close(file);
}

// Everything a stream yields, channel-major per block, concatenated per channel.
std::vector<std::vector<float>> ReadAll(SampleStream& stream, int64_t block_frames) {
  std::vector<std::vector<float>> channels(stream.channel_count());
  std::vector<float> block;
  while (true) {
    auto n = stream.Read(block_frames, &block);
    EXPECT_TRUE(n.ok()) << n.status().ToString();
    if (!n.ok() || *n == 0) break;
    for (int c = 0; c < stream.channel_count(); ++c) {
      channels[c].insert(channels[c].end(), block.begin() + c * *n, block.begin() + (c + 1) * *n);
    }
  }
  return channels;
}

RawPcmOptions Options(const std::string& path, RawPcmFormat format) {
  RawPcmOptions o;
  o.path = path;
  o.format = format;
  o.channel_count = kChannels;
  o.sample_rate_hz = kRateHz;
  return o;
}

// The same codes through WavStream and RawPcmStream, compared bit for bit (memcmp: a float
// equal in value but not in bits would also differ in the estimates' last digits).
void ExpectSameAsWav(const std::string& wav_path, const std::string& raw_path, RawPcmFormat format) {
  auto wav = WavStream::Open({wav_path});
  ASSERT_TRUE(wav.ok()) << wav.status().ToString();
  auto raw = RawPcmStream::Open(Options(raw_path, format));
  ASSERT_TRUE(raw.ok()) << raw.status().ToString();
  EXPECT_EQ((*raw)->total_frames(), wav->total_frames());
  const auto from_wav = ReadAll(*wav, 1000);
  const auto from_raw = ReadAll(**raw, 777);  // a different block size: blocks must not matter
  for (int c = 0; c < kChannels; ++c) {
    ASSERT_EQ(from_raw[c].size(), from_wav[c].size());
    EXPECT_EQ(std::memcmp(from_raw[c].data(), from_wav[c].data(), from_wav[c].size() * sizeof(float)), 0)
        << RawPcmFormatName(format) << " channel " << c;
  }
}

TEST(RawPcm, S16leEqualsTheWavReaderBitForBit) {
  TempDir dir;
  std::mt19937 rng(16);
  std::uniform_int_distribution<int> code(-32768, 32767);
  std::vector<int16_t> samples = {-32768, 32767, 0, 1, -1, 16384, -16384, 12345, -321};  // 3 frames
  for (int i = 0; i < 3 * 2001; ++i) samples.push_back(static_cast<int16_t>(code(rng)));
  std::string bytes;
  for (int16_t s : samples) AppendLe(static_cast<uint16_t>(s), 2, &bytes);
  WriteWav(dir.File("s16.wav"), SF_FORMAT_PCM_16, samples);
  WriteBytes(dir.File("s16.raw"), bytes);
  ExpectSameAsWav(dir.File("s16.wav"), dir.File("s16.raw"), RawPcmFormat::kS16le);

  // And the scaling itself: code / 32768.
  auto raw = RawPcmStream::Open(Options(dir.File("s16.raw"), RawPcmFormat::kS16le));
  ASSERT_TRUE(raw.ok());
  std::vector<float> block;
  ASSERT_EQ(*(*raw)->Read(3, &block), 3);
  // Channel-major: channel 0 holds -32768, 1, -16384; channel 1 32767, -1, 12345; channel 2 0, 16384, -321.
  EXPECT_EQ(block[0], -1.0f);
  EXPECT_EQ(block[3 + 0], 32767.0f / 32768.0f);
  EXPECT_EQ(block[3 + 1], -1.0f / 32768.0f);
  EXPECT_EQ(block[6 + 1], 0.5f);
}

TEST(RawPcm, S32leEqualsTheWavReaderBitForBit) {
  TempDir dir;
  std::mt19937 rng(32);
  std::uniform_int_distribution<int32_t> code(std::numeric_limits<int32_t>::min(), std::numeric_limits<int32_t>::max());
  // Extremes, and codes whose float rounding matters (2^24 + 1 is not a float).
  std::vector<int32_t> samples = {std::numeric_limits<int32_t>::min(),
                                  std::numeric_limits<int32_t>::max(),
                                  0,
                                  (1 << 24) + 1,
                                  -(1 << 24) - 1,
                                  1 << 30};
  for (int i = 0; i < 3 * 2000; ++i) samples.push_back(code(rng));
  std::string bytes;
  for (int32_t s : samples) AppendLe(static_cast<uint32_t>(s), 4, &bytes);
  WriteWav(dir.File("s32.wav"), SF_FORMAT_PCM_32, samples);
  WriteBytes(dir.File("s32.raw"), bytes);
  ExpectSameAsWav(dir.File("s32.wav"), dir.File("s32.raw"), RawPcmFormat::kS32le);

  auto raw = RawPcmStream::Open(Options(dir.File("s32.raw"), RawPcmFormat::kS32le));
  ASSERT_TRUE(raw.ok());
  std::vector<float> block;
  ASSERT_EQ(*(*raw)->Read(2, &block), 2);
  // Channel-major: channel 0 holds codes INT32_MIN, 2^24 + 1; channel 1 INT32_MAX, ...
  EXPECT_EQ(block[0], -1.0f);
  EXPECT_EQ(block[1], 0.0078125f) << "2^24 + 1 rounds to the float 2^24 first, as in libsndfile";
  EXPECT_EQ(block[2], 1.0f) << "INT32_MAX rounds to the float 2^31";
  EXPECT_EQ(block[5], 0.5f);  // channel 2, frame 1: 2^30
}

TEST(RawPcm, F32leIsPassedOnAsStoredNonFiniteIncluded) {
  TempDir dir;
  std::mt19937 rng(3232);
  std::normal_distribution<float> normal(0.0f, 0.5f);
  std::vector<float> samples = {-1.0f, 1.0f, 0.0f, 3.5f, -7.25f, 1e-30f};  // beyond +-1: not clipped
  for (int i = 0; i < 3 * 1500; ++i) samples.push_back(normal(rng));
  std::string bytes;
  for (float s : samples) AppendLe(std::bit_cast<uint32_t>(s), 4, &bytes);
  WriteWav(dir.File("f32.wav"), SF_FORMAT_FLOAT, samples);
  WriteBytes(dir.File("f32.raw"), bytes);
  ExpectSameAsWav(dir.File("f32.wav"), dir.File("f32.raw"), RawPcmFormat::kF32le);

  // Non-finite values reach the caller, as from a float WAV; the session rejects the block.
  std::string odd;
  for (float s : {std::numeric_limits<float>::quiet_NaN(), std::numeric_limits<float>::infinity(), 0.25f}) {
    AppendLe(std::bit_cast<uint32_t>(s), 4, &odd);
  }
  WriteBytes(dir.File("odd.raw"), odd);
  auto raw = RawPcmStream::Open(Options(dir.File("odd.raw"), RawPcmFormat::kF32le));
  ASSERT_TRUE(raw.ok());
  std::vector<float> block;
  ASSERT_EQ(*(*raw)->Read(10, &block), 1);
  EXPECT_TRUE(std::isnan(block[0]));
  EXPECT_TRUE(std::isinf(block[1]));
  EXPECT_EQ(block[2], 0.25f);
}

// A FIFO stands for `producer | localizer-cli track --raw -`: the reader sees a pipe
// (unknown length) that delivers bytes in pieces that split frames.
void WriteFifoInPieces(const std::string& path, const std::string& bytes, size_t piece_bytes) {
  const int fd = ::open(path.c_str(), O_WRONLY);
  if (fd < 0) return;
  for (size_t at = 0; at < bytes.size(); at += piece_bytes) {
    const size_t n = std::min(piece_bytes, bytes.size() - at);
    if (::write(fd, bytes.data() + at, n) != static_cast<ssize_t>(n)) break;
  }
  ::close(fd);
}

TEST(RawPcm, APipeIsReadInBlocksWhateverPiecesItArrivesIn) {
  TempDir dir;
  const std::string fifo = dir.File("pipe");
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  std::string bytes;
  const int frames = 1000;
  for (int n = 0; n < frames; ++n) {
    for (int c = 0; c < kChannels; ++c) AppendLe(static_cast<uint16_t>(n * 10 + c), 2, &bytes);
  }
  std::thread producer(WriteFifoInPieces, fifo, bytes, 7);  // 7 bytes: never a whole frame
  auto raw = RawPcmStream::Open(Options(fifo, RawPcmFormat::kS16le));
  ASSERT_TRUE(raw.ok()) << raw.status().ToString();
  EXPECT_EQ((*raw)->total_frames(), 0) << "a pipe's length is unknown";
  std::vector<float> block;
  std::vector<int64_t> sizes;
  while (true) {
    auto n = (*raw)->Read(300, &block);
    ASSERT_TRUE(n.ok()) << n.status().ToString();
    if (*n == 0) break;
    sizes.push_back(*n);
    // Channel 2 of the block's last frame: code (frame * 10 + 2).
    const int64_t last = (*raw)->frames_read() - 1;
    EXPECT_EQ(block[2 * *n + *n - 1], static_cast<float>(last * 10 + 2) / 32768.0f);
  }
  producer.join();
  EXPECT_EQ(sizes, (std::vector<int64_t>{300, 300, 300, 100})) << "full blocks until the end";
  EXPECT_EQ((*raw)->frames_read(), frames);
}

TEST(RawPcm, ATrailingPartialFrameInAPipeIsAnErrorAfterTheWholeFrames) {
  TempDir dir;
  const std::string fifo = dir.File("pipe");
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  const std::string bytes(10 * kChannels * 2 + 3, '\0');  // 10 frames of s16le and 3 bytes
  std::thread producer(WriteFifoInPieces, fifo, bytes, 64);
  auto raw = RawPcmStream::Open(Options(fifo, RawPcmFormat::kS16le));
  ASSERT_TRUE(raw.ok());
  std::vector<float> block;
  auto first = (*raw)->Read(100, &block);
  ASSERT_TRUE(first.ok()) << first.status().ToString();
  EXPECT_EQ(*first, 10) << "the whole frames come first";
  auto second = (*raw)->Read(100, &block);
  producer.join();
  ASSERT_FALSE(second.ok());
  const std::string message = second.status().message();
  EXPECT_NE(message.find("3 byte(s) left over"), std::string::npos) << message;
  EXPECT_NE(message.find("6 bytes"), std::string::npos) << message;  // the frame size
  EXPECT_NE(message.find("after 10 whole frames"), std::string::npos) << message;
  EXPECT_NE(message.find("--channels"), std::string::npos) << message;
}

TEST(RawPcm, ATrailingPartialFrameInAFileIsRefusedAtOpen) {
  TempDir dir;
  WriteBytes(dir.File("odd.raw"), std::string(5 * kChannels * 4 + 5, '\0'));
  auto raw = RawPcmStream::Open(Options(dir.File("odd.raw"), RawPcmFormat::kF32le));
  ASSERT_FALSE(raw.ok());
  EXPECT_NE(raw.status().message().find("5 byte(s) left over"), std::string::npos) << raw.status().message();
  EXPECT_NE(raw.status().message().find(dir.File("odd.raw")), std::string::npos);
}

TEST(RawPcm, BadOptionsAndInputsAreNamed) {
  TempDir dir;
  WriteBytes(dir.File("ok.raw"), std::string(12, '\0'));
  auto format = ParseRawPcmFormat("s24le");
  ASSERT_FALSE(format.ok());
  EXPECT_NE(format.status().message().find("s16le, s32le or f32le"), std::string::npos);
  EXPECT_EQ(*ParseRawPcmFormat("f32le"), RawPcmFormat::kF32le);

  RawPcmOptions o = Options(dir.File("ok.raw"), RawPcmFormat::kS16le);
  o.channel_count = 0;
  EXPECT_NE(RawPcmStream::Open(o).status().message().find("channel_count is 0"), std::string::npos);
  o = Options(dir.File("ok.raw"), RawPcmFormat::kS16le);
  for (double rate : {0.0, -8000.0, std::nan("")}) {
    o.sample_rate_hz = rate;
    EXPECT_NE(RawPcmStream::Open(o).status().message().find("sample_rate_hz"), std::string::npos) << rate;
  }
  o = Options("", RawPcmFormat::kS16le);
  EXPECT_FALSE(RawPcmStream::Open(o).ok());
  auto missing = RawPcmStream::Open(Options(dir.File("nope.raw"), RawPcmFormat::kS16le));
  EXPECT_EQ(missing.status().code(), StatusCode::kNotFound);
  auto directory = RawPcmStream::Open(Options(dir.path().string(), RawPcmFormat::kS16le));
  EXPECT_NE(directory.status().message().find("is a directory"), std::string::npos);
  auto ok = RawPcmStream::Open(Options(dir.File("ok.raw"), RawPcmFormat::kS16le));
  ASSERT_TRUE(ok.ok());
  EXPECT_EQ((*ok)->total_frames(), 2);
  std::vector<float> block;
  EXPECT_FALSE((*ok)->Read(0, &block).ok()) << "max_frames must be > 0";
}

}  // namespace
}  // namespace localizer::io
