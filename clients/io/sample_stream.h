// A multichannel recording read block by block, whatever holds it: what `localizer-cli
// track` streams through a session, locally (track_runner.h) or to a server
// (clients/grpc/remote_track.h). One runner serves every input kind; an input kind is one
// implementation:
//   WavStream     (wav_io.h)   one multichannel WAV or a set of mono WAVs, via libsndfile
//   RawPcmStream  (raw_pcm.h)  headerless interleaved PCM from a file or standard input
//   AlsaCaptureStream (alsa_capture.h)  live capture from an ALSA PCM device
// Every implementation returns float32 samples with integer PCM scaled to full scale 1.0 the
// way libsndfile does (wav_io.h), so the same samples give the same estimates whichever way
// they arrive. Not thread-safe per object.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "engine/core/status.h"

namespace localizer::io {

class SampleStream {
 public:
  virtual ~SampleStream() = default;

  virtual double sample_rate_hz() const = 0;
  virtual int channel_count() const = 0;
  // Samples per channel in the whole recording, or 0 when that is not known ahead (raw PCM
  // from a pipe); progress reports need it.
  virtual int64_t total_frames() const = 0;
  // Names the input in messages: "signals.wav", "a.wav + 5 more", "stdin (--raw -)".
  virtual std::string Describe() const = 0;
  // Where sample_rate_hz() came from, for the note when the array file says otherwise:
  // "the WAV header's rate", "--sample-rate".
  virtual std::string RateOrigin() const = 0;

  // Reads up to `max_frames` (> 0) per channel, resizes `channel_major` to channel_count * n
  // and fills it channel-major (sample i of channel c at [c * n + i]); returns n, which is 0
  // only at the end of the recording. An error names the input and where in it.
  virtual StatusOr<int64_t> Read(int64_t max_frames, std::vector<float>* channel_major) = 0;

  // A live input can lose samples (a capture overrun: the device's buffer filled before it
  // was read). Samples per channel lost just before the block the latest Read returned, so
  // that the runner tells the session (engine::Session::Skip) and the estimates' times stay
  // those of the samples; a file loses nothing.
  virtual int64_t frames_lost_before_last_read() const { return 0; }
  // Over the whole run: how many times samples were lost, and how many per channel.
  virtual int64_t overrun_count() const { return 0; }
  virtual int64_t frames_lost() const { return 0; }
};

}  // namespace localizer::io
