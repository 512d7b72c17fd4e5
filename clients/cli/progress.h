// Progress of a long `track` run on stderr: percent, samples per channel, and audio seconds
// processed per wall second. On a terminal one line is rewritten in place (at most 4 times
// a second); into a file or pipe a line is printed every 10 %, so logs stay short.
#pragma once

#include "clients/io/track_runner.h"

namespace localizer::cli {

class ProgressReporter {
 public:
  // Reports nothing for recordings shorter than `min_audio_s`.
  explicit ProgressReporter(double min_audio_s = 5.0);
  void Update(const io::TrackProgress& progress);
  // Ends the in-place line on a terminal.
  void Finish();

 private:
  void Print(const io::TrackProgress& progress, int percent);

  double min_audio_s_;
  bool terminal_;
  bool printed_ = false;
  int last_decile_ = -1;
  double last_print_wall_s_ = -1.0;
};

}  // namespace localizer::cli
