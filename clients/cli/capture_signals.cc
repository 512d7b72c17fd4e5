#include "clients/cli/capture_signals.h"

#include <atomic>
#include <csignal>

namespace localizer::cli {

// Live capture ends cleanly on SIGINT or SIGTERM: the handler only raises the flag the
// capture polls (alsa_capture.h), so the blocks read so far are tracked, the estimates file
// is closed and the summary printed. A second signal is not fatal, because senders such as
// timeout(1) signal the process and its group, i.e. twice; a third kills as usual.
namespace {

std::atomic<bool> stop_capture{false};
std::atomic<int> stop_signal{0};
std::atomic<int> stop_signals_received{0};
static_assert(std::atomic<bool>::is_always_lock_free && std::atomic<int>::is_always_lock_free,
              "set from a signal handler");

extern "C" void OnStopSignal(int signal_number) {
  if (stop_signals_received.fetch_add(1) >= 2) {
    std::signal(signal_number, SIG_DFL);  // both async-signal-safe
    std::raise(signal_number);
    return;
  }
  if (stop_signal.load() == 0) stop_signal.store(signal_number);
  stop_capture.store(true);
}

}  // namespace

void InstallCaptureStopHandlers() {
  struct sigaction action {};
  action.sa_handler = OnStopSignal;
  sigemptyset(&action.sa_mask);
  action.sa_flags = 0;  // the capture polls the flag every wait slice (100 ms) anyway
  sigaction(SIGINT, &action, nullptr);
  sigaction(SIGTERM, &action, nullptr);
}

const std::atomic<bool>* CaptureStopFlag() { return &stop_capture; }

const char* CaptureStopReason(double duration_s) {
  const int signal_number = stop_signal.load();
  if (signal_number == SIGINT) return "SIGINT";
  if (signal_number == SIGTERM) return "SIGTERM";
  return duration_s > 0 ? "duration" : "end";
}

}  // namespace localizer::cli
