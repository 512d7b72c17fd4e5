// What `localizer-loadgen` runs: its flags, their defaults and units, and their checks.
//
// The session parameters and their defaults are loadtest.py's (clients/python/loadtest.py),
// so that the two generators load a server alike and their numbers can be set side by side.
#pragma once

#include <string>

#include "clients/grpc/connection.h"
#include "clients/grpc/streamer.h"
#include "engine/core/flags.h"
#include "engine/core/status.h"

namespace localizer::loadgen {

struct LoadOptions {
  // Where and how.
  std::string target;              // HOST:PORT (required)
  client::ConnectOptions connect;  // --tls-ca, --tls-cert, --tls-key, --auth-token-file
  int sessions = 0;                // concurrent Track sessions, >= 1 (required)
  double duration_s = 0.0;         // streaming time of each session after its start, > 0 (required)
  std::string rate;                // "realtime" | "max" (required)
  double ramp_s = 0.0;             // session starts spread over this; 0: over one block
                                   // period in realtime, all at once at max
  int threads = 1;                 // pacing threads, each driving sessions i % threads
  int connections = 0;             // TCP connections; 0: one per 100 sessions
  double drain_timeout_s = 30.0;   // after the half-close, wait this long for the end
  std::string json_path;           // result file; "": stdout

  // What every session sends (loadtest.py's defaults).
  int channels = 4;  // sensors, >= 4: a 1.5 m tetrahedron, then a ring
  double sample_rate_hz = 44100.0;
  int frame_samples = 4096;        // GCC frame, samples
  int hop_samples = 2048;          // frame advance, samples
  int block_samples = 4096;        // per channel per block
  int particles = 4096;            // particle filter size
  std::string motion = "default";  // "default" (the server's) | "one-std" (the GPU filter's)
  std::string encoding = "float";  // "float" (SampleBlock.samples) | "pcm16"
  std::string backend = "auto";    // the session's backend: "auto", "cpu", "gpu"
  int seed = 1;                    // signal seed; session i's config has seed + i
  double signal_seconds = 4.0;     // length of the recording every session loops

  // Filled by Validate from `rate` and `encoding`.
  client::Pacing pacing = client::Pacing::kRealtime;
  bool pcm16 = false;

  // Seconds of audio in one block.
  double block_period_s() const { return block_samples / sample_rate_hz; }
  // The connections the sessions are spread over.
  int connection_count() const;

  // INVALID_ARGUMENT naming the flag ("--hop must be in [1, frame], got 5000"); on success
  // sets `pacing` and `pcm16`.
  Status Validate();
};

// Registers every flag above on `flags`, bound to `options` (whose current values are the
// defaults printed by --help).
void RegisterLoadFlags(FlagSet& flags, LoadOptions* options);

}  // namespace localizer::loadgen
