// The Python keyword options of localizer.engine.Session -> engine::AudioSessionConfig, with the
// defaults and couplings localizer-cli applies (clients/cli/session_flags.cc), so that the same
// options here and the same flags there open the same session:
//   - every numeric default is engine::AudioSessionConfig's;
//   - one motion noise and TDOA noise for every filter (accel_noise_mps2, tdoa_sigma_s go to
//     the particle and the Kalman filters alike, and the Kalman filters take the particle
//     filter's min_peak_snr);
//   - frame_samples / hop_samples unset: 4096 / 2048, except for sessions that list sources,
//     which get about 32 ms (the power of two nearest 0.032 x the rate) and half of it.
// Units are in the names (SI; tdoa_sigma_s in seconds where the CLI takes microseconds).
// The array file's "session" object (clients/io/session_file.h, localizer/session_file.py) uses
// these names as its keys for the options a CLI flag covers: renaming an option renames a key.
#pragma once

#include <pybind11/pybind11.h>

#include "engine/pipeline/session_config.h"

namespace localizer::python {

namespace py = pybind11;

// INVALID_ARGUMENT (ValueError) for an unknown option name, a value of the wrong type or a
// name the engine does not know (filter, weighting, ...). Checks nothing the engine checks.
engine::AudioSessionConfig SessionConfigFrom(const py::handle& sensors_m, double sample_rate_hz,
                                             const py::dict& options);

// The options and their defaults, as SessionConfigFrom applies them (None: see above).
py::dict DefaultSessionOptions();

// The config a session resolved, under the option names (plus localization resolved).
py::dict SessionConfigToDict(const engine::AudioSessionConfig& config);

}  // namespace localizer::python
