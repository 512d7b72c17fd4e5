// AlsaCaptureStream in a build without ALSA (CMake did not find libasound2-dev): the
// `--alsa` flag still exists and says how to get it, rather than vanishing from the help.
#include "clients/io/alsa_capture.h"

namespace localizer::io {

bool AlsaCaptureAvailable() { return false; }

AlsaCaptureStream::AlsaCaptureStream(const AlsaCaptureOptions& options) : options_(options) {}
AlsaCaptureStream::~AlsaCaptureStream() = default;

std::string AlsaCaptureStream::Describe() const { return "ALSA device '" + options_.device + "'"; }

StatusOr<std::unique_ptr<AlsaCaptureStream>> AlsaCaptureStream::Open(const AlsaCaptureOptions& options) {
  return FailedPrecondition("ALSA device '" + options.device + "': " + kAlsaUnavailableMessage);
}

StatusOr<std::unique_ptr<AlsaCaptureStream>> AlsaCaptureStream::Adopt(_snd_pcm* /*pcm*/,
                                                                      const AlsaCaptureOptions& options) {
  return Open(options);
}

StatusOr<int64_t> AlsaCaptureStream::Read(int64_t /*max_frames*/, std::vector<float>* /*channel_major*/) {
  return FailedPrecondition(Describe() + ": " + kAlsaUnavailableMessage);
}

}  // namespace localizer::io
