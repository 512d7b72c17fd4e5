// How `localizer-cli track --alsa` stops on SIGINT and SIGTERM: cleanly, through a flag the
// capture polls (clients/io/alsa_capture.h), so that the blocks read so far are tracked, the
// estimates file is complete and the summary is printed.
#pragma once

#include <atomic>

namespace localizer::cli {

// Installs the handlers for SIGINT and SIGTERM (process-wide; for the rest of the run).
void InstallCaptureStopHandlers();
// The flag they raise, for AlsaCaptureOptions::stop.
const std::atomic<bool>* CaptureStopFlag();
// Why the capture ended: "SIGINT", "SIGTERM", else "duration" (duration_s > 0) or "end".
const char* CaptureStopReason(double duration_s);

}  // namespace localizer::cli
