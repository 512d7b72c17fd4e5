// Live audio in: `localizer-cli track --alsa DEVICE` (docs/CLI.md, "Live capture") reads an ALSA
// PCM capture device through libasound2, block by block, as the SampleStream the tracker
// runs on (sample_stream.h). The alternative without this code is a pipe:
//     arecord -D DEVICE -t raw -f S16_LE -c 4 -r 48000 | localizer-cli track --raw - ...
// which loses overruns silently (arecord prints them, the tracker cannot see them); here
// every overrun becomes a gap the session skips, so estimate times stay true.
//
// Setup: interleaved access, exactly `channel_count` channels and `sample_rate_hz` (ALSA's
// own resampling turned off): a device that cannot give them exactly is refused with the
// device's name and what it offers, never resampled or remixed behind the tracker's back (a
// "plughw:" or "plug" device may still convert on the user's explicit choice). The sample
// format is S16_LE, S32_LE or FLOAT_LE: the one asked for, or the best the device offers
// (S32_LE, then FLOAT_LE, then S16_LE). Samples are scaled as raw PCM and WAV samples are
// (raw_pcm.h: s16 / 32768, s32 / 2^31), so the same codes give the same estimates.
//
// Reading: the device is opened non-blocking and waited on in slices of at most 100 ms, so
// that a stop request (a signal handler setting `stop`) ends the stream within one slice,
// and a device that delivers nothing ends it with "no samples from DEVICE for N s" instead
// of hanging. Read fills the whole block unless the stream ends, so blocks (and estimates)
// do not depend on how the device's periods fall.
//
// Overruns (-EPIPE: the buffer filled before it was read; -ESTRPIPE: a suspend): the device
// is prepared and started again, the overrun counted, and the samples lost estimated from the
// monotonic clock: those the buffer held at the last successful read plus the rate times the
// time from that read to the restart. The estimate is as good as the clock calls' timing
// (tens of microseconds, about one sample at 48 kHz). The loss is reported before the next
// block (frames_lost_before_last_read) and the runner skips it in the session.
//
// End: after `duration_s` of stream time (samples read plus samples lost), on a stop request
// (the samples read so far are returned, then 0), or never otherwise (a device has no end;
// ALSA's `file` plugin, too, goes on after its infile ends, repeating stale data, so give it
// a duration).
//
// Errors: every ALSA failure is INVALID_ARGUMENT (opening, setup) or UNAVAILABLE (while
// reading), with the device name, snd_strerror's text and ALSA's own last message; ALSA's
// printing to stderr is replaced by that (a process-wide handler, installed by Open). Built
// without ALSA (libasound2-dev missing at configure time) Open is FAILED_PRECONDITION
// saying so. Not thread-safe per object.
#pragma once

#include <atomic>
#include <climits>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "clients/io/raw_pcm.h"
#include "clients/io/sample_stream.h"
#include "engine/core/status.h"

struct _snd_pcm;  // NOLINT(bugprone-reserved-identifier): ALSA's own name for snd_pcm_t, kept out of this header

namespace localizer::io {

// Whether this build can capture (CMake found libasound2-dev).
bool AlsaCaptureAvailable();
// What the flag says without ALSA: "built without ALSA (install libasound2-dev)".
extern const char* const kAlsaUnavailableMessage;

enum class AlsaSampleFormat { kBest, kS16, kS32, kF32 };
// "s16", "s32", "f32", or "best"; anything else is INVALID_ARGUMENT listing them.
StatusOr<AlsaSampleFormat> ParseAlsaSampleFormat(const std::string& name);
const char* AlsaSampleFormatName(AlsaSampleFormat format);

struct AlsaCaptureOptions {
  std::string device;           // an ALSA PCM name: "hw:1,0", "plughw:CARD=Array", "default", a name from .asoundrc
  std::string config_text;      // non-empty: look `device` up in this ALSA configuration text instead of the system's
  int channel_count = 0;        // exactly, [1, kMaxRawPcmChannels]
  double sample_rate_hz = 0.0;  // exactly; a whole number of Hz
  AlsaSampleFormat format = AlsaSampleFormat::kBest;
  double period_s = 0.02;          // the device's period (wake-up interval), asked for; the device may round it
  double buffer_s = 0.5;           // the device's ring buffer, asked for: how long the tracker may stall without loss
  double duration_s = 0.0;         // stream time after which the stream ends; 0: until stopped
  double no_data_timeout_s = 5.0;  // no samples for this long: UNAVAILABLE
  const std::atomic<bool>* stop = nullptr;  // set (e.g. by a SIGINT handler) to end the stream cleanly

  Status Validate() const;  // INVALID_ARGUMENT naming the field and value
};

class AlsaCaptureStream final : public SampleStream {
 public:
  // Opens and configures the device (nothing is read yet; the capture starts at the first Read).
  static StatusOr<std::unique_ptr<AlsaCaptureStream>> Open(const AlsaCaptureOptions& options);
  // Takes a PCM opened elsewhere (an in-process plugin, e.g. a test's ioplug device) and
  // configures it as Open would; `options.device` names it in messages. Closes it on error too.
  static StatusOr<std::unique_ptr<AlsaCaptureStream>> Adopt(_snd_pcm* pcm, const AlsaCaptureOptions& options);
  ~AlsaCaptureStream() override;
  AlsaCaptureStream(const AlsaCaptureStream&) = delete;
  AlsaCaptureStream& operator=(const AlsaCaptureStream&) = delete;

  double sample_rate_hz() const override { return options_.sample_rate_hz; }
  int channel_count() const override { return options_.channel_count; }
  int64_t total_frames() const override { return duration_frames_; }  // 0: until stopped
  // "ALSA device 'hw:1,0'".
  std::string Describe() const override;
  std::string RateOrigin() const override { return "--sample-rate (the device runs at it exactly)"; }
  StatusOr<int64_t> Read(int64_t max_frames, std::vector<float>* channel_major) override;

  int64_t frames_lost_before_last_read() const override { return gap_before_last_read_; }
  int64_t overrun_count() const override { return overruns_; }
  int64_t frames_lost() const override { return frames_lost_; }
  int64_t frames_read() const { return frames_read_; }
  RawPcmFormat sample_format() const { return format_; }    // what the device delivers
  int64_t period_frames() const { return period_frames_; }  // as the device set them
  int64_t buffer_frames() const { return buffer_frames_; }

 private:
  explicit AlsaCaptureStream(const AlsaCaptureOptions& options);
  Status Configure();
  Status Error(StatusCode code, const std::string& what, int alsa_error) const;  // alsa_error 0: none
  void NoteRead();  // after a successful read: the time, and what the buffer still holds
  // After an overrun or a suspend: restart the device, count the loss and return it (frames).
  StatusOr<int64_t> Recover(int alsa_error);
  int64_t RemainingFrames() const;  // of duration_s; INT64_MAX without a limit
  bool stop_requested() const;

  AlsaCaptureOptions options_;
  _snd_pcm* pcm_ = nullptr;
  RawPcmFormat format_ = RawPcmFormat::kS16le;
  int64_t period_frames_ = 0;
  int64_t buffer_frames_ = 0;
  int64_t duration_frames_ = 0;  // 0: no limit
  bool started_ = false;
  bool ended_ = false;
  int64_t frames_read_ = 0;
  int64_t frames_lost_ = 0;
  int64_t overruns_ = 0;
  int64_t gap_pending_ = 0;  // lost after the frames of the block being returned: goes before the next
  int64_t gap_before_last_read_ = 0;
  // At the last successful read (or the start): the monotonic time and the frames the buffer still held.
  double last_read_time_s_ = 0.0;
  int64_t buffered_at_last_read_ = 0;
  std::vector<unsigned char> raw_;  // one block of interleaved codes, reused
};

}  // namespace localizer::io
