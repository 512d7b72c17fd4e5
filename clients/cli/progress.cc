#include "clients/cli/progress.h"

#include <unistd.h>

#include <cstdio>

namespace localizer::cli {

ProgressReporter::ProgressReporter(double min_audio_s)
    : min_audio_s_(min_audio_s), terminal_(isatty(STDERR_FILENO) != 0) {}

void ProgressReporter::Update(const io::TrackProgress& p) {
  if (p.frames_total <= 0 || p.sample_rate_hz <= 0) return;
  if (static_cast<double>(p.frames_total) / p.sample_rate_hz < min_audio_s_) return;
  const int percent = static_cast<int>(100 * p.frames_done / p.frames_total);
  const bool done = p.frames_done >= p.frames_total;
  if (terminal_) {
    if (done || p.wall_s - last_print_wall_s_ >= 0.25) Print(p, percent);
    return;
  }
  const int decile = percent / 10;
  if (decile > last_decile_) {
    last_decile_ = decile;
    Print(p, percent);
  }
}

void ProgressReporter::Print(const io::TrackProgress& p, int percent) {
  const double audio_s = static_cast<double>(p.frames_done) / p.sample_rate_hz;
  const double speed = p.wall_s > 0 ? audio_s / p.wall_s : 0.0;
  std::fprintf(stderr, "%strack: %3d%%  %lld/%lld samples per channel, %.1f audio s per wall s%s",
               terminal_ ? "\r" : "", percent, static_cast<long long>(p.frames_done),
               static_cast<long long>(p.frames_total), speed, terminal_ ? "" : "\n");
  std::fflush(stderr);
  printed_ = true;
  last_print_wall_s_ = p.wall_s;
}

void ProgressReporter::Finish() {
  if (terminal_ && printed_) std::fputc('\n', stderr);
}

}  // namespace localizer::cli
