// Near-field scenes for positions from planar and linear arrays (issue 18), shared by the
// session tests and the near-field report: white-noise sources rendered in a shoebox room
// (engine/sim/room.h) with sensor noise, fed to a Session in blocks, and the reference the
// issue's goal names: a per-frame least-squares fix on every pair's GCC-PHAT peak.
#pragma once

#include <cstdint>
#include <vector>

#include "engine/core/estimate.h"
#include "engine/core/types.h"
#include "engine/pipeline/session.h"
#include "engine/sim/room.h"

namespace localizer::engine::testing {

struct NearFieldScene {
  ShoeboxRoom room;  // rt60_s 0: free field
  std::vector<Vec3> sensors_m;
  std::vector<Vec3> sources_m;
  double sample_rate_hz = 16000.0;
  double seconds = 2.0;
  // Sensor noise: white, this many dB below a source's direct sound at 1 m.
  double snr_db = 20.0;
  uint64_t seed = 1;
};

// Channel-major samples (sensors x samples) of the scene.
std::vector<float> RenderNearFieldScene(const NearFieldScene& scene);

// The session's estimates over the whole recording, fed in blocks of 4096 samples.
std::vector<Estimate> StreamThrough(Session* session, const std::vector<float>& samples, int sensors);

// Per frame (frame_samples long, every hop_samples from sample 0, as a Session frames): each
// pair's GCC-PHAT peak over the whole band (the largest of its lags within the array's
// travel time, refined on the continuous GCC), then Gauss-Newton on the plain sum of squared
// lag residuals over all pairs, started at `truth_m` (the most favourable start) and held in
// the plane through truth_m with normal `plane_normal` when that is not zero. One fix per
// frame.
std::vector<Vec3> LeastSquaresFixes(const std::vector<float>& samples, const std::vector<Vec3>& sensors_m,
                                    double sample_rate_hz, double sound_speed_mps, int frame_samples,
                                    int hop_samples, const Vec3& truth_m, const Vec3& plane_normal);

double Median(std::vector<double> values);  // NaN when empty

}  // namespace localizer::engine::testing
