#include "clients/io/wav_io.h"

#include <sndfile.h>

#include <algorithm>
#include <climits>
#include <cmath>
#include <filesystem>
#include <utility>

namespace localizer::io {

namespace {

// Interleaved frames to channel-major. With the channel count known at compile time the
// loop vectorises (the runtime-count loop ran one scalar load and store per sample: ~4 % of
// `localizer-cli track`'s CPU on a 4-channel file).
template <int kChannels>
void DeinterleaveFixed(const float* __restrict in, int64_t frames, float* __restrict out) {
  for (int64_t n = 0; n < frames; ++n) {
    for (int c = 0; c < kChannels; ++c) out[c * frames + n] = in[n * kChannels + c];
  }
}

void Deinterleave(const float* in, int64_t frames, int channels, float* out) {
  switch (channels) {
    case 1:
      return DeinterleaveFixed<1>(in, frames, out);
    case 2:
      return DeinterleaveFixed<2>(in, frames, out);
    case 3:
      return DeinterleaveFixed<3>(in, frames, out);
    case 4:
      return DeinterleaveFixed<4>(in, frames, out);
    case 6:
      return DeinterleaveFixed<6>(in, frames, out);
    case 8:
      return DeinterleaveFixed<8>(in, frames, out);
    default:
      break;
  }
  for (int64_t n = 0; n < frames; ++n) {
    for (int c = 0; c < channels; ++c) out[c * frames + n] = in[n * channels + c];
  }
}

struct SndfileCloser {
  void operator()(SNDFILE* file) const { sf_close(file); }
};
using SndfilePtr = std::unique_ptr<SNDFILE, SndfileCloser>;

std::string SndfileError(SNDFILE* file) { return sf_strerror(file); }

// Opens `path` for reading with integer PCM normalised to full scale 1.0.
StatusOr<std::pair<SndfilePtr, SF_INFO>> OpenForReading(const std::string& path) {
  std::error_code ignored;
  if (!std::filesystem::exists(path, ignored)) return NotFound(path + ": no such file");
  SF_INFO info{};
  SndfilePtr file(sf_open(path.c_str(), SFM_READ, &info));
  if (!file) {
    return InvalidArgument(path + ": not a readable sound file (libsndfile: " + SndfileError(nullptr) + ")");
  }
  if (info.samplerate <= 0 || info.channels <= 0) {
    return InvalidArgument(path + ": header gives sample rate " + std::to_string(info.samplerate) + " Hz and " +
                           std::to_string(info.channels) + " channels");
  }
  // Explicit although it is libsndfile's default: our scaling contract depends on it.
  sf_command(file.get(), SFC_SET_NORM_FLOAT, nullptr, SF_TRUE);
  return std::make_pair(std::move(file), info);
}

Status ShortRead(const std::string& path, SNDFILE* file, sf_count_t got, int64_t wanted, int64_t at_frame) {
  return InvalidArgument(path + ": read " + std::to_string(got) + " of " + std::to_string(wanted) +
                         " frames at frame " + std::to_string(at_frame) + " (" + SndfileError(file) + ")");
}

}  // namespace

struct WavStream::File {
  std::string path;
  SndfilePtr handle;
  SF_INFO info{};
};

WavStream::WavStream(WavStream&&) noexcept = default;
WavStream& WavStream::operator=(WavStream&&) noexcept = default;
WavStream::~WavStream() = default;

namespace {

// Checks that a set of mono files forms one recording; returns the common length and,
// in `warning`, a note when the files are truncated to the shortest.
template <typename FileT>
StatusOr<int64_t> CheckMonoSet(const std::vector<FileT>& files, std::string* warning) {
  const FileT& first = files.front();
  const FileT* shortest = &first;
  const FileT* longest = &first;
  for (const FileT& f : files) {
    if (f.info.channels != 1) {
      return InvalidArgument(f.path + ": has " + std::to_string(f.info.channels) +
                             " channels; a set of several files needs one mono file per sensor");
    }
    if (f.info.samplerate != first.info.samplerate) {
      return InvalidArgument(f.path + " is sampled at " + std::to_string(f.info.samplerate) + " Hz but " + first.path +
                             " at " + std::to_string(first.info.samplerate) + " Hz");
    }
    if (f.info.frames < shortest->info.frames) shortest = &f;
    if (f.info.frames > longest->info.frames) longest = &f;
  }
  const int64_t spread = longest->info.frames - shortest->info.frames;
  const double spread_s = static_cast<double>(spread) / first.info.samplerate;
  const std::string lengths = longest->path + " has " + std::to_string(longest->info.frames) + " frames, " +
                              shortest->path + " has " + std::to_string(shortest->info.frames);
  if (spread_s > kMaxSetLengthMismatchS) {
    return InvalidArgument(lengths + ": they differ by " + std::to_string(spread_s) + " s, more than " +
                           std::to_string(kMaxSetLengthMismatchS) + " s, so they are not one recording");
  }
  warning->clear();
  if (spread > 0) {
    *warning = lengths + ": all files truncated to " + std::to_string(shortest->info.frames) + " frames (" +
               std::to_string(spread) + " dropped from the longest)";
  }
  return static_cast<int64_t>(shortest->info.frames);
}

}  // namespace

StatusOr<WavStream> WavStream::Open(const std::vector<std::string>& paths) {
  if (paths.empty()) return InvalidArgument("no WAV file given");
  WavStream stream;
  for (const std::string& path : paths) {
    auto opened = OpenForReading(path);
    if (!opened.ok()) return opened.status();
    stream.files_.push_back(File{path, std::move(opened->first), opened->second});
  }
  const SF_INFO& info = stream.files_.front().info;
  stream.sample_rate_hz_ = info.samplerate;
  if (stream.files_.size() == 1) {
    stream.channel_count_ = info.channels;
    stream.total_frames_ = info.frames;
  } else {
    auto frames = CheckMonoSet(stream.files_, &stream.warning_);
    if (!frames.ok()) return frames.status();
    stream.channel_count_ = static_cast<int>(stream.files_.size());
    stream.total_frames_ = *frames;
  }
  return stream;
}

std::string WavStream::Describe() const {
  if (files_.empty()) return "(closed)";
  if (files_.size() == 1) return files_.front().path;
  return files_.front().path + " + " + std::to_string(files_.size() - 1) + " more";
}

StatusOr<int64_t> WavStream::Read(int64_t max_frames, std::vector<float>* channel_major) {
  if (max_frames <= 0) return InvalidArgument("max_frames is " + std::to_string(max_frames));
  const int64_t frames = std::min(max_frames, total_frames_ - frames_read_);
  channel_major->resize(static_cast<size_t>(channel_count_) * std::max<int64_t>(frames, 0));
  if (frames <= 0) return int64_t{0};
  const Status status =
      files_.size() == 1 ? ReadInterleaved(frames, channel_major) : ReadMonoSet(frames, channel_major);
  if (!status.ok()) return status;
  frames_read_ += frames;
  return frames;
}

// libsndfile returns interleaved frames; the engine wants channel-major.
Status WavStream::ReadInterleaved(int64_t frames, std::vector<float>* channel_major) {
  File& file = files_.front();
  interleaved_.resize(static_cast<size_t>(frames) * channel_count_);
  const sf_count_t got = sf_readf_float(file.handle.get(), interleaved_.data(), frames);
  if (got != frames) {
    return ShortRead(file.path, file.handle.get(), got, frames, frames_read_);
  }
  Deinterleave(interleaved_.data(), frames, channel_count_, channel_major->data());
  return Status::Ok();
}

// Mono files read straight into their channel's slot.
Status WavStream::ReadMonoSet(int64_t frames, std::vector<float>* channel_major) {
  for (size_t c = 0; c < files_.size(); ++c) {
    File& file = files_[c];
    float* slot = channel_major->data() + c * frames;
    const sf_count_t got = sf_readf_float(file.handle.get(), slot, frames);
    if (got != frames) {
      return ShortRead(file.path, file.handle.get(), got, frames, frames_read_);
    }
  }
  return Status::Ok();
}

StatusOr<Recording> ReadWavSet(const std::vector<std::string>& paths, std::string* warning) {
  auto stream = WavStream::Open(paths);
  if (!stream.ok()) return stream.status();
  if (warning != nullptr) *warning = stream->warning();
  Recording recording;
  recording.sample_rate_hz = stream->sample_rate_hz();
  recording.channel_count = stream->channel_count();
  recording.frames = stream->total_frames();
  if (recording.frames == 0) return recording;
  auto got = stream->Read(recording.frames, &recording.samples);
  if (!got.ok()) return got.status();
  return recording;
}

StatusOr<Recording> ReadWav(const std::string& path) { return ReadWavSet({path}, nullptr); }

namespace {

Status CheckWritable(const std::string& path, double rate_hz, int channel_count, int64_t frames) {
  if (!(rate_hz >= 1.0 && rate_hz <= INT_MAX && rate_hz == std::floor(rate_hz))) {
    return InvalidArgument(path + ": sample_rate_hz " + std::to_string(rate_hz) +
                           " is not a positive integer, which WAV requires");
  }
  if (channel_count <= 0 || frames < 0) {
    return InvalidArgument(path + ": cannot write " + std::to_string(channel_count) + " channels x " +
                           std::to_string(frames) + " frames");
  }
  return Status::Ok();
}

}  // namespace

Status WriteWavFloat(const std::string& path, const Recording& recording) {
  if (recording.samples.size() !=
      static_cast<size_t>(std::max(recording.channel_count, 0)) * std::max<int64_t>(recording.frames, 0)) {
    return InvalidArgument(path + ": recording has " + std::to_string(recording.samples.size()) + " samples for " +
                           std::to_string(recording.channel_count) + " channels x " + std::to_string(recording.frames) +
                           " frames");
  }
  return WriteWavFloat(path, recording.sample_rate_hz, recording.channel_count, recording.frames,
                       recording.samples.data());
}

Status WriteWavFloat(const std::string& path, double sample_rate_hz, int channel_count, int64_t frames,
                     const float* channel_major) {
  LOCALIZER_RETURN_IF_ERROR(CheckWritable(path, sample_rate_hz, channel_count, frames));
  SF_INFO info{};
  info.samplerate = static_cast<int>(sample_rate_hz);
  info.channels = channel_count;
  info.format = SF_FORMAT_WAV | SF_FORMAT_FLOAT;
  SndfilePtr file(sf_open(path.c_str(), SFM_WRITE, &info));
  if (!file) {
    return InvalidArgument(path + ": cannot write (libsndfile: " + SndfileError(nullptr) + ")");
  }
  // Interleave in chunks so a long recording does not need a second full copy.
  constexpr int64_t kChunkFrames = 1 << 16;
  std::vector<float> interleaved;
  for (int64_t start = 0; start < frames; start += kChunkFrames) {
    const int64_t n = std::min(kChunkFrames, frames - start);
    interleaved.resize(static_cast<size_t>(n) * channel_count);
    for (int64_t i = 0; i < n; ++i) {
      for (int c = 0; c < channel_count; ++c) {
        interleaved[i * channel_count + c] = channel_major[c * frames + start + i];
      }
    }
    if (sf_writef_float(file.get(), interleaved.data(), n) != n) {
      return InvalidArgument(path + ": write failed (libsndfile: " + SndfileError(file.get()) + ")");
    }
  }
  // Closing writes the final header sizes; report a failure rather than leave a broken file.
  if (sf_close(file.release()) != 0) return InvalidArgument(path + ": closing failed");
  return Status::Ok();
}

}  // namespace localizer::io
