// A capture device without a sound card, for the capture tests: an in-process ALSA
// "ioplug" PCM (libasound's external-plugin interface, no shared object needed) that runs in
// real time on the monotonic clock, offers exactly one channel count, one rate and S16_LE,
// and delivers a counter: frame n (counted from the first start, in device time) holds
// n & 0xFFFF on channel 0 and n >> 16 on channel 1 (two channels), so the reader can tell
// which frames it received and which were lost. When the reader falls a whole buffer
// behind, the device overruns (its pointer callback reports -EPIPE) as a card does; frames
// keep being "captured" in device time while it is stopped, so a restart resumes at the
// frame the clock says. `stalled` makes it deliver nothing, ever.
#pragma once

#include <alsa/asoundlib.h>
extern "C" {  // this header, unlike asoundlib.h's, does not say so itself
#include <alsa/pcm_ioplug.h>
}
#include <sys/timerfd.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <memory>
#include <string>

namespace localizer::io::testing {

class FakeAlsaDevice {
 public:
  // Returns the PCM (owned by the caller: snd_pcm_close, e.g. through AlsaCaptureStream::Adopt)
  // or nullptr with *error set. The object must outlive the PCM.
  snd_pcm_t* Open(unsigned channels, unsigned rate_hz, bool stalled, std::string* error) {
    channels_ = channels;
    rate_hz_ = rate_hz;
    stalled_ = stalled;
    // The poll descriptor: a timer every 2 ms, so that a wait wakes up to look at the clock.
    timer_fd_ = timerfd_create(CLOCK_MONOTONIC, TFD_NONBLOCK | TFD_CLOEXEC);
    itimerspec every{{0, 2'000'000}, {0, 2'000'000}};
    timerfd_settime(timer_fd_, 0, &every, nullptr);
    callbacks_.start = &Start;
    callbacks_.stop = &Stop;
    callbacks_.pointer = &Pointer;
    callbacks_.transfer = &Transfer;
    callbacks_.prepare = &Prepare;
    callbacks_.poll_revents = &PollRevents;
    callbacks_.close = &Close;
    io_.version = SND_PCM_IOPLUG_VERSION;
    io_.name = "localizer fake capture device";
    io_.callback = &callbacks_;
    io_.private_data = this;
    io_.poll_fd = timer_fd_;
    io_.poll_events = POLLIN;
    io_.mmap_rw = 0;
    int err = snd_pcm_ioplug_create(&io_, "fake", SND_PCM_STREAM_CAPTURE, SND_PCM_NONBLOCK);
    if (err < 0) {
      *error = std::string("snd_pcm_ioplug_create: ") + snd_strerror(err);
      return nullptr;
    }
    const unsigned access[] = {SND_PCM_ACCESS_RW_INTERLEAVED};
    const unsigned formats[] = {SND_PCM_FORMAT_S16_LE};
    const unsigned channel_list[] = {channels};
    const unsigned rates[] = {rate_hz};
    if ((err = snd_pcm_ioplug_set_param_list(&io_, SND_PCM_IOPLUG_HW_ACCESS, 1, access)) < 0 ||
        (err = snd_pcm_ioplug_set_param_list(&io_, SND_PCM_IOPLUG_HW_FORMAT, 1, formats)) < 0 ||
        (err = snd_pcm_ioplug_set_param_list(&io_, SND_PCM_IOPLUG_HW_CHANNELS, 1, channel_list)) < 0 ||
        (err = snd_pcm_ioplug_set_param_list(&io_, SND_PCM_IOPLUG_HW_RATE, 1, rates)) < 0 ||
        (err = snd_pcm_ioplug_set_param_minmax(&io_, SND_PCM_IOPLUG_HW_PERIOD_BYTES, 16, 1 << 20)) < 0 ||
        (err = snd_pcm_ioplug_set_param_minmax(&io_, SND_PCM_IOPLUG_HW_BUFFER_BYTES, 64, 1 << 22)) < 0 ||
        (err = snd_pcm_ioplug_set_param_minmax(&io_, SND_PCM_IOPLUG_HW_PERIODS, 2, 1024)) < 0) {
      *error = std::string("snd_pcm_ioplug_set_param: ") + snd_strerror(err);
      snd_pcm_ioplug_delete(&io_);
      return nullptr;
    }
    return io_.pcm;
  }

  ~FakeAlsaDevice() {
    if (timer_fd_ >= 0) ::close(timer_fd_);
  }

  int overruns() const { return overruns_; }
  // The device-time frame index a sample pair (channel 0, channel 1) encodes.
  static int64_t FrameIndexOf(float ch0, float ch1) {
    const auto lo = static_cast<uint16_t>(static_cast<int16_t>(std::lround(ch0 * 32768.0f)));
    const auto hi = static_cast<uint16_t>(static_cast<int16_t>(std::lround(ch1 * 32768.0f)));
    return static_cast<int64_t>(hi) << 16 | lo;
  }

 private:
  static FakeAlsaDevice* Self(snd_pcm_ioplug_t* io) { return static_cast<FakeAlsaDevice*>(io->private_data); }
  static double Now() {
    return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
  }
  // Frames the device has captured since the first start, by its clock.
  int64_t DeviceFrames(double t) const { return static_cast<int64_t>(std::floor((t - first_start_s_) * rate_hz_)); }

  static int Start(snd_pcm_ioplug_t* io) {
    FakeAlsaDevice* d = Self(io);
    const double now = Now();
    if (d->first_start_s_ < 0) d->first_start_s_ = now;
    d->base_frame_ = d->DeviceFrames(now);  // frame 0 of this run, in device time
    d->delivered_ = 0;
    d->xrun_ = false;
    return 0;
  }
  static int Stop(snd_pcm_ioplug_t* /*io*/) { return 0; }
  static int Prepare(snd_pcm_ioplug_t* io) {
    Self(io)->delivered_ = 0;
    Self(io)->xrun_ = false;
    return 0;
  }
  static int Close(snd_pcm_ioplug_t* /*io*/) { return 0; }
  // The hardware position (in the ring); -EPIPE once the reader is more than a buffer behind.
  static snd_pcm_sframes_t Pointer(snd_pcm_ioplug_t* io) {
    FakeAlsaDevice* d = Self(io);
    if (d->xrun_) return -EPIPE;
    if (io->state != SND_PCM_STATE_RUNNING || d->stalled_)
      return static_cast<snd_pcm_sframes_t>(d->delivered_ % io->buffer_size);
    const int64_t captured = d->DeviceFrames(Now()) - d->base_frame_;
    if (captured - d->delivered_ >= static_cast<int64_t>(io->buffer_size)) {  // full: as stop_threshold does
      d->xrun_ = true;
      ++d->overruns_;
      return -EPIPE;
    }
    return static_cast<snd_pcm_sframes_t>(captured % static_cast<int64_t>(io->buffer_size));
  }
  static snd_pcm_sframes_t Transfer(snd_pcm_ioplug_t* io, const snd_pcm_channel_area_t* areas, snd_pcm_uframes_t offset,
                                    snd_pcm_uframes_t size) {
    FakeAlsaDevice* d = Self(io);
    for (snd_pcm_uframes_t k = 0; k < size; ++k) {
      const int64_t n = d->base_frame_ + d->delivered_ + static_cast<int64_t>(k);
      for (unsigned c = 0; c < io->channels; ++c) {
        const snd_pcm_channel_area_t& a = areas[c];
        auto* sample = reinterpret_cast<int16_t*>(static_cast<char*>(a.addr) + (a.first + (offset + k) * a.step) / 8);
        const uint16_t code = c == 0 ? static_cast<uint16_t>(n & 0xFFFF) : c == 1 ? static_cast<uint16_t>(n >> 16) : 0;
        std::memcpy(sample, &code, sizeof(code));
      }
    }
    d->delivered_ += static_cast<int64_t>(size);
    return static_cast<snd_pcm_sframes_t>(size);
  }
  static int PollRevents(snd_pcm_ioplug_t* io, struct pollfd* pfd, unsigned int /*nfds*/, unsigned short* revents) {
    uint64_t ticks = 0;
    (void)::read(Self(io)->timer_fd_, &ticks, sizeof(ticks));  // re-arm: the timer stays readable otherwise
    *revents = pfd[0].revents & POLLIN;
    return 0;
  }

  snd_pcm_ioplug_t io_{};
  snd_pcm_ioplug_callback_t callbacks_{};
  int timer_fd_ = -1;
  unsigned channels_ = 0;
  unsigned rate_hz_ = 0;
  bool stalled_ = false;
  double first_start_s_ = -1.0;
  int64_t base_frame_ = 0;  // device frame of this run's first frame
  int64_t delivered_ = 0;   // frames handed to the reader in this run
  bool xrun_ = false;
  int overruns_ = 0;
};

}  // namespace localizer::io::testing
