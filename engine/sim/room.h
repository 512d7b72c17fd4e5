// Shoebox room acoustics by the image-source method (Allen & Berkley 1979): impulse
// responses from a point source to each sensor, and signals rendered through them.
//
// The room is [0, Lx] x [0, Ly] x [0, Lz] (metres). Every wall reflects pressure with the
// same coefficient beta = sqrt(1 - alpha). The energy absorption alpha is found by bisection
// so that the image lattice's own energy decay, for a source and a receiver at fixed
// fractions of the room off its centre (images binned by arrival, each (1 - alpha)^k / d^2,
// Schroeder's backward integral, -5 to -25 dB, x 3), lasts the requested RT60. Eyring's formula, RT60 = 24 ln(10) V /
// (c S (-ln(1 - alpha))), assumes a diffuse field. A shoebox with equal walls is not one:
// images along its longest axis reflect least and dominate the late decay, and with
// Eyring's alpha the decay measured 1.55x too long at 0.2, 0.4 and 0.6 s in a 6 x 5 x 3 m room.
// The image of index (n, p) in Z^3 x {0,1}^3 lies at
//     x = (1 - 2 p_x) s_x + 2 n_x Lx   (y, z alike)
// after |n_x - p_x| + |n_x| reflections off the two x walls (and y, z alike); sensor m hears
// it as beta^(reflections) / (4 pi d) delta(t - d / c), d = |image - m|, written into the
// impulse response as a band-limited impulse (a Kaiser-windowed sinc, 64 taps, centred at the
// fractional sample d fs / c). The direct path is the image (0, 0). Images arriving after
// max_delay_s are left out. A reverberant response is then high-passed (2nd-order Butterworth,
// 80 Hz): every image adds a positive impulse, and without it the dense late response builds
// up a DC level that decays slower than the reflections (measured: T20 1.25-1.37x the
// lattice's); Allen & Berkley high-pass theirs for the same reason. Anechoic ones are not.
//
// Cost: the images within c max_delay_s of the source, about 4/3 pi (c T)^3 / V (for
// 0.3 s in a 90 m^3 room, 50 000), times 64 taps per sensor; rendering is one FFT
// convolution per source and sensor. Static sources only.
#pragma once

#include <cstdint>
#include <vector>

#include "engine/core/status.h"
#include "engine/core/types.h"

namespace localizer::engine {

struct ShoeboxRoom {
  Vec3 size_m = Vec3(6.0, 5.0, 3.0);
  double rt60_s = 0.3;  // 0: anechoic (the direct path alone)
  double sound_speed_mps = 343.0;

  // INVALID_ARGUMENT naming the field: sizes positive and finite, RT60 in [0, 2] s.
  Status Validate() const;
  // The calibrated alpha for rt60_s (above), in (0, 1); 1 when anechoic (no reflection).
  // Costs a few milliseconds (30 passes over the lattice up to 0.75 RT60).
  double WallAbsorption() const;
};

// One impulse response per sensor, each `length_samples` long (h[m][n], n = 0 at emission).
// max_delay_s: 0 takes the RT60 (anechoic: the direct path's delay plus 64 taps).
// INVALID_ARGUMENT for a source or sensor outside the room, a non-positive rate or length.
StatusOr<std::vector<std::vector<double>>> RoomImpulseResponses(const ShoeboxRoom& room, const Vec3& source_m,
                                                                const std::vector<Vec3>& sensors_m,
                                                                double sample_rate_hz, double max_delay_s = 0.0);

struct RoomSource {
  Vec3 position_m = Vec3::Zero();
  std::vector<double> signal;  // emitted, at the sample rate, from t = 0
};

// What the sensors record over [0, samples) per channel, channel-major: every source's signal
// through its impulse responses, summed. No noise.
StatusOr<std::vector<float>> RenderInRoom(const ShoeboxRoom& room, const std::vector<RoomSource>& sources,
                                          const std::vector<Vec3>& sensors_m, double sample_rate_hz, int64_t samples);

}  // namespace localizer::engine
