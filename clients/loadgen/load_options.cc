#include "clients/loadgen/load_options.h"

#include <algorithm>

namespace localizer::loadgen {

namespace {

// loadtest.py's rule: one connection per this many sessions unless --connections says.
constexpr int kSessionsPerConnection = 100;

std::string Got(double value) { return ", got " + FormatDouble(value); }

}  // namespace

int LoadOptions::connection_count() const {
  if (connections > 0) return std::min(connections, sessions);
  return std::max(1, (sessions + kSessionsPerConnection - 1) / kSessionsPerConnection);
}

Status LoadOptions::Validate() {
  auto pacing_value = client::ParsePacing(rate);
  if (!pacing_value.ok()) return InvalidArgument("--rate: " + pacing_value.status().message());
  pacing = *pacing_value;
  auto encoding_value = client::ParseEncoding(encoding);
  if (!encoding_value.ok()) return InvalidArgument("--encoding: " + encoding_value.status().message());
  pcm16 = *encoding_value == client::Encoding::kPcm16;
  if (target.empty()) return InvalidArgument("--target must not be empty");
  if (sessions < 1) return InvalidArgument("--sessions must be >= 1" + Got(sessions));
  if (!(duration_s > 0.0)) return InvalidArgument("--duration must be > 0" + Got(duration_s));
  if (!(ramp_s >= 0.0)) return InvalidArgument("--ramp must be >= 0" + Got(ramp_s));
  if (threads < 1 || threads > sessions) {
    return InvalidArgument("--threads must be in [1, sessions]" + Got(threads));
  }
  if (connections < 0) return InvalidArgument("--connections must be >= 0" + Got(connections));
  if (!(drain_timeout_s > 0.0)) return InvalidArgument("--drain-timeout must be > 0" + Got(drain_timeout_s));
  if (channels < 4) return InvalidArgument("--channels must be >= 4 (a 3-D fix needs 4 sensors)" + Got(channels));
  if (!(sample_rate_hz > 0.0)) return InvalidArgument("--sample-rate must be > 0" + Got(sample_rate_hz));
  if (frame_samples < 64) return InvalidArgument("--frame must be >= 64" + Got(frame_samples));
  if (hop_samples < 1 || hop_samples > frame_samples) {
    return InvalidArgument("--hop must be in [1, frame]" + Got(hop_samples));
  }
  if (block_samples < 1) return InvalidArgument("--block must be >= 1" + Got(block_samples));
  if (particles < 16) return InvalidArgument("--particles must be >= 16" + Got(particles));
  if (motion != "default" && motion != "one-std") {
    return InvalidArgument("--motion must be default or one-std, got \"" + motion + "\"");
  }
  if (seed < 0) return InvalidArgument("--seed must be >= 0" + Got(seed));
  if (!(signal_seconds > 0.0)) return InvalidArgument("--signal-seconds must be > 0" + Got(signal_seconds));
  if (signal_seconds * sample_rate_hz > 1e8) {
    return InvalidArgument("--signal-seconds x --sample-rate must be <= 1e8 samples" +
                           Got(signal_seconds * sample_rate_hz));
  }
  return Status::Ok();
}

void RegisterLoadFlags(FlagSet& flags, LoadOptions* o) {
  flags.String("target", &o->target, "HOST:PORT", "localizer-server address").Required();
  flags.String("tls-ca", &o->connect.tls_ca, "FILE",
               "connect over TLS, verifying the server against these PEM CA certificates");
  flags.String("tls-cert", &o->connect.tls_cert, "FILE",
               "PEM client certificate for mutual TLS (with --tls-key; implies TLS)");
  flags.String("tls-key", &o->connect.tls_key, "FILE", "PEM private key of --tls-cert");
  flags.String("auth-token-file", &o->connect.auth_token_file, "FILE",
               "file holding the bearer token sent on every stream (first non-'#' line)");
  // Required flags have no default to print.
  flags.Int("sessions", &o->sessions, "N", "", "concurrent Track sessions").Required().default_text.clear();
  flags.Double("duration", &o->duration_s, "S", "s", "seconds each session streams, from its start in the ramp")
      .Required()
      .default_text.clear();
  flags
      .String("rate", &o->rate, "RATE",
              "realtime (one block per block duration, on an absolute schedule) | max (as fast as "
              "gRPC flow control allows)")
      .Required();
  flags.Double("ramp", &o->ramp_s, "S", "s",
               "spread session starts over this many seconds (0: over one block period in realtime, "
               "at once at max)");
  flags.Int("threads", &o->threads, "N", "",
            "pacing threads, each driving sessions i % N (gRPC's own threads do the reads)");
  flags.Int("connections", &o->connections, "N", "", "TCP connections to spread sessions over (0: one per 100)");
  flags.Double("drain-timeout", &o->drain_timeout_s, "S", "s",
               "after half-closing, cancel a stream that has not ended within this");
  flags.String("json", &o->json_path, "FILE", "write the JSON result here instead of stdout");
  flags.Int("channels", &o->channels, "N", "", "sensors (>= 4; the first 4: a 1.5 m tetrahedron)");
  flags.Double("sample-rate", &o->sample_rate_hz, "HZ", "Hz", "samples per second per channel");
  flags.Int("frame", &o->frame_samples, "N", "samples", "GCC frame");
  flags.Int("hop", &o->hop_samples, "N", "samples", "frame advance");
  flags.Int("block", &o->block_samples, "N", "samples", "samples per channel per block");
  flags.Int("particles", &o->particles, "N", "", "particle filter size");
  flags.String("motion", &o->motion, "M",
               "particle filter motion: default (the server's: acceleration levels, turn rates, speed changes) | "
               "one-std (one acceleration std, the GPU filter's)");
  flags.String("encoding", &o->encoding, "ENC", "float (SampleBlock.samples) | pcm16 (pcm_s16le)");
  flags.String("backend", &o->backend, "NAME", "session backend: auto | cpu | gpu");
  flags.Int("seed", &o->seed, "N", "", "signal seed; session i's config uses seed + i");
  flags.Double("signal-seconds", &o->signal_seconds, "S", "s", "length of the recording every session loops");
}

}  // namespace localizer::loadgen
