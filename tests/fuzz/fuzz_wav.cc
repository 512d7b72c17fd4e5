// A WAV (or any sound file libsndfile opens) -> ReadWav, and the same file read in chunks
// through WavStream, as `localizer-cli track` reads a recording. An accepted file has a
// positive rate and channel count, channel_count * frames samples, and the chunked read
// gives the same samples as the whole one.
#include "clients/io/wav_io.h"
#include "fuzz_checks.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace localizer;
  static fuzz::MemFile file;
  const std::string& path = file.Write(data, size);
  auto recording = io::ReadWav(path);
  if (!recording.ok()) {
    FUZZ_CHECK(recording.status().code() == StatusCode::kInvalidArgument, recording.status().ToString());
    return 0;
  }
  FUZZ_CHECK(recording->sample_rate_hz > 0.0 && recording->channel_count >= 1 && recording->frames >= 0, "header");
  FUZZ_CHECK(recording->samples.size() == static_cast<size_t>(recording->channel_count) * recording->frames,
             std::to_string(recording->samples.size()) + " samples for " + std::to_string(recording->channel_count) +
                 " x " + std::to_string(recording->frames));
  auto stream = io::WavStream::Open({path});
  FUZZ_CHECK(stream.ok(), stream.status().ToString());
  FUZZ_CHECK(stream->total_frames() == recording->frames && stream->channel_count() == recording->channel_count,
             "stream header");
  std::vector<float> chunk;
  int64_t at = 0;
  while (true) {
    auto got = stream->Read(97, &chunk);
    FUZZ_CHECK(got.ok(), got.status().ToString());
    if (*got == 0) break;
    for (int c = 0; c < recording->channel_count; ++c) {
      for (int64_t i = 0; i < *got; ++i) {
        const float a = chunk[static_cast<size_t>(c * *got + i)];
        const float b = recording->channel(c)[at + i];
        FUZZ_CHECK(a == b || (std::isnan(a) && std::isnan(b)), "chunked read differs");
      }
    }
    at += *got;
  }
  FUZZ_CHECK(at == recording->frames, "chunked read length");
  return 0;
}
