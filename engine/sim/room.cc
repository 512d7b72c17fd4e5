#include "engine/sim/room.h"

#include <algorithm>
#include <cmath>
#include <complex>
#include <limits>
#include <numbers>
#include <string>

#include "engine/sim/kaiser_window.h"
#include "engine/tdoa/fftw_util.h"

namespace localizer::engine {
namespace {
constexpr int kHalfTaps = 32;  // the band-limited impulse: 64 taps
constexpr double kKaiserBeta = 8.0;

bool Inside(const Vec3& p, const Vec3& size) {
  return p.allFinite() && (p.array() > 0.0).all() && (p.array() < size.array()).all();
}

// The windowed sinc tabulated at kPhases fractional offsets (linear between them): row f
// holds the 2 kHalfTaps taps for an impulse at floor + f / kPhases.
constexpr int kPhases = 512;
const std::vector<double>& KernelTable() {
  static const std::vector<double> table = [] {
    std::vector<double> t(static_cast<size_t>((kPhases + 1) * 2 * kHalfTaps));
    for (int f = 0; f <= kPhases; ++f) {
      for (int j = 0; j < 2 * kHalfTaps; ++j) {
        const double u = (j - kHalfTaps + 1) - static_cast<double>(f) / kPhases;  // tap - impulse
        const double sinc = std::abs(u) < 1e-12 ? 1.0 : std::sin(std::numbers::pi * u) / (std::numbers::pi * u);
        t[static_cast<size_t>(f) * 2 * kHalfTaps + static_cast<size_t>(j)] =
            sinc * KaiserWindow(u / kHalfTaps, kKaiserBeta);
      }
    }
    return t;
  }();
  return table;
}

// Adds amplitude x (a band-limited impulse at fractional sample `at`) into h.
void AddImpulse(double at, double amplitude, std::vector<double>* h) {
  const std::vector<double>& table = KernelTable();
  const double floor_at = std::floor(at);
  const double phase = (at - floor_at) * kPhases;
  const auto f = static_cast<int>(phase);
  const double w = phase - f;
  const double* row0 = &table[static_cast<size_t>(f) * 2 * kHalfTaps];
  const double* row1 = &table[static_cast<size_t>(std::min(f + 1, kPhases)) * 2 * kHalfTaps];
  const auto first = static_cast<long>(floor_at) - kHalfTaps + 1;
  const long size = static_cast<long>(h->size());
  for (int j = 0; j < 2 * kHalfTaps; ++j) {
    const long n = first + j;
    if (n < 0 || n >= size) continue;
    (*h)[static_cast<size_t>(n)] += amplitude * ((1.0 - w) * row0[j] + w * row1[j]);
  }
}
// A 2nd-order Butterworth high-pass at kHighPassHz (bilinear transform), in place. Every
// image adds a positive impulse, so the dense late response builds up a spurious DC level
// that decays slower than the reflections themselves (Allen & Berkley high-pass theirs too).
constexpr double kHighPassHz = 80.0;
void HighPass(double sample_rate_hz, std::vector<double>* h) {
  const double k = std::tan(std::numbers::pi * kHighPassHz / sample_rate_hz), q = std::numbers::sqrt2 / 2.0;
  const double norm = 1.0 / (1.0 + k / q + k * k);
  const double b0 = norm, b1 = -2.0 * norm, b2 = norm;
  const double a1 = 2.0 * (k * k - 1.0) * norm, a2 = (1.0 - k / q + k * k) * norm;
  double x1 = 0.0, x2 = 0.0, y1 = 0.0, y2 = 0.0;
  for (double& v : *h) {
    const double y = b0 * v + b1 * x1 + b2 * x2 - a1 * y1 - a2 * y2;
    x2 = x1;
    x1 = v;
    y2 = y1;
    y1 = y;
    v = y;
  }
}
}  // namespace

Status ShoeboxRoom::Validate() const {
  if (!size_m.allFinite() || (size_m.array() <= 0.0).any()) return InvalidArgument("room size_m must be positive");
  if (!(rt60_s >= 0.0) || rt60_s > 2.0) return InvalidArgument("room rt60_s must be in [0, 2] s");
  if (!(sound_speed_mps > 0.0) || !std::isfinite(sound_speed_mps))
    return InvalidArgument("room sound_speed_mps must be positive");
  return Status::Ok();
}

namespace {

// The image lattice's energy by arrival time (1 ms bins) and reflection count, for a source
// and a receiver at fixed fractions of the room (off its centre and off each other's symmetry
// planes: a receiver at the source makes the direct path infinite): sum of 1 / d^2. Absorption
// only weighs the counts, so the lattice is walked once for every alpha tried.
constexpr double kBin_s = 1e-3;
std::vector<std::vector<double>> LatticeEnergy(const ShoeboxRoom& room, double horizon_s) {
  const double c = room.sound_speed_mps;
  const Vec3 source = room.size_m.cwiseProduct(Vec3(0.35, 0.4, 0.45));
  const Vec3 receiver = room.size_m.cwiseProduct(Vec3(0.65, 0.55, 0.6));
  const Eigen::Array3i orders = (c * horizon_s / (2.0 * room.size_m.array())).ceil().cast<int>() + 1;
  const int max_reflections = 2 * orders.sum() + 3;
  std::vector<std::vector<double>> energy(static_cast<size_t>(std::ceil(horizon_s / kBin_s)) + 1,
                                          std::vector<double>(static_cast<size_t>(max_reflections) + 1, 0.0));
  for (int nx = -orders.x(); nx <= orders.x(); ++nx)
    for (int ny = -orders.y(); ny <= orders.y(); ++ny)
      for (int nz = -orders.z(); nz <= orders.z(); ++nz)
        for (int p = 0; p < 8; ++p) {
          const Eigen::Array3i n(nx, ny, nz), parity(p & 1, (p >> 1) & 1, (p >> 2) & 1);
          const Vec3 image =
              (1.0 - 2.0 * parity.cast<double>()) * source.array() + 2.0 * n.cast<double>() * room.size_m.array();
          const double d = (image - receiver).norm();
          const auto bin = static_cast<size_t>(d / c / kBin_s);
          if (bin >= energy.size()) continue;
          const auto reflections = static_cast<size_t>((n - parity).abs().sum() + n.abs().sum());
          energy[bin][reflections] += 1.0 / (d * d);
        }
  return energy;
}

// Schroeder's T20 (x 3) of the lattice's energy at one alpha; +inf when it never falls 25 dB.
double LatticeT20(const std::vector<std::vector<double>>& energy, double alpha) {
  std::vector<double> keep(energy.front().size(), 1.0);
  for (size_t k = 1; k < keep.size(); ++k) keep[k] = keep[k - 1] * (1.0 - alpha);
  std::vector<double> tail(energy.size() + 1, 0.0);
  for (size_t i = energy.size(); i-- > 0;) {
    double sum = 0.0;
    for (size_t k = 0; k < keep.size(); ++k) sum += keep[k] * energy[i][k];
    tail[i] = tail[i + 1] + sum;
  }
  double t5 = -1.0;
  for (size_t i = 0; i < energy.size(); ++i) {
    const double db = 10.0 * std::log10(tail[i] / tail[0]);
    if (t5 < 0.0 && db <= -5.0) t5 = static_cast<double>(i) * kBin_s;
    if (db <= -25.0) return 3.0 * (static_cast<double>(i) * kBin_s - t5);
  }
  return std::numeric_limits<double>::infinity();
}

}  // namespace

double ShoeboxRoom::WallAbsorption() const {
  if (rt60_s <= 0.0) return 1.0;
  // Bisection on alpha: the decay shortens as alpha grows. The backward integral runs to
  // 1.2 RT60 (the impulse responses' length when asked for their tail, as the tests do).
  const std::vector<std::vector<double>> energy = LatticeEnergy(*this, 1.2 * rt60_s);
  double lo = 1e-4, hi = 0.9999;
  for (int i = 0; i < 30; ++i) {
    const double mid = 0.5 * (lo + hi);
    (LatticeT20(energy, mid) > rt60_s ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

namespace {

// RoomImpulseResponses with the walls' pressure reflection coefficient given (the absorption's
// calibration costs milliseconds: RenderInRoom makes it once for all its sources).
StatusOr<std::vector<std::vector<double>>> ImpulseResponses(const ShoeboxRoom& room, double beta, const Vec3& source_m,
                                                            const std::vector<Vec3>& sensors_m, double sample_rate_hz,
                                                            double max_delay_s) {
  if (!(sample_rate_hz > 0.0) || !std::isfinite(sample_rate_hz))
    return InvalidArgument("sample_rate_hz must be positive");
  if (!Inside(source_m, room.size_m)) return InvalidArgument("the source is not inside the room");
  for (size_t m = 0; m < sensors_m.size(); ++m)
    if (!Inside(sensors_m[m], room.size_m))
      return InvalidArgument("sensor " + std::to_string(m) + " is not inside the room");
  const double c = room.sound_speed_mps;
  const bool anechoic = room.rt60_s <= 0.0;
  double farthest_m = 0.0;
  for (const Vec3& m : sensors_m) farthest_m = std::max(farthest_m, (m - source_m).norm());
  if (!(max_delay_s > 0.0)) max_delay_s = anechoic ? farthest_m / c : room.rt60_s;
  const auto length = static_cast<size_t>(std::ceil(max_delay_s * sample_rate_hz)) + 2 * kHalfTaps;
  if (length > (size_t{1} << 26)) return InvalidArgument("the impulse responses would exceed 2^26 samples");
  std::vector<std::vector<double>> h(sensors_m.size(), std::vector<double>(length, 0.0));
  const double reach_m = c * max_delay_s + room.size_m.norm();
  const Eigen::Array3i orders = (reach_m / (2.0 * room.size_m.array())).ceil().cast<int>();
  for (int nx = -orders.x(); nx <= orders.x(); ++nx)
    for (int ny = -orders.y(); ny <= orders.y(); ++ny)
      for (int nz = -orders.z(); nz <= orders.z(); ++nz)
        for (int p = 0; p < 8; ++p) {
          const Eigen::Array3i n(nx, ny, nz), parity(p & 1, (p >> 1) & 1, (p >> 2) & 1);
          const int reflections = (n - parity).abs().sum() + n.abs().sum();
          if (anechoic && reflections > 0) continue;
          const Vec3 image =
              (1.0 - 2.0 * parity.cast<double>()) * source_m.array() + 2.0 * n.cast<double>() * room.size_m.array();
          const double gain = std::pow(beta, reflections);
          for (size_t m = 0; m < sensors_m.size(); ++m) {
            const double d = (image - sensors_m[m]).norm();
            if (d / c > max_delay_s + (anechoic ? 1e-12 : 0.0)) continue;
            AddImpulse(d / c * sample_rate_hz, gain / (4.0 * std::numbers::pi * d), &h[m]);
          }
        }
  if (!anechoic)
    for (std::vector<double>& response : h) HighPass(sample_rate_hz, &response);
  return h;
}

double ReflectionCoefficient(const ShoeboxRoom& room) { return std::sqrt(1.0 - room.WallAbsorption()); }

}  // namespace

StatusOr<std::vector<std::vector<double>>> RoomImpulseResponses(const ShoeboxRoom& room, const Vec3& source_m,
                                                                const std::vector<Vec3>& sensors_m,
                                                                double sample_rate_hz, double max_delay_s) {
  LOCALIZER_RETURN_IF_ERROR(room.Validate());
  return ImpulseResponses(room, ReflectionCoefficient(room), source_m, sensors_m, sample_rate_hz, max_delay_s);
}

StatusOr<std::vector<float>> RenderInRoom(const ShoeboxRoom& room, const std::vector<RoomSource>& sources,
                                          const std::vector<Vec3>& sensors_m, double sample_rate_hz, int64_t samples) {
  LOCALIZER_RETURN_IF_ERROR(room.Validate());
  if (samples < 1 || samples > (int64_t{1} << 28)) return InvalidArgument("samples must be in [1, 2^28]");
  const double beta = ReflectionCoefficient(room);
  std::vector<double> out(sensors_m.size() * static_cast<size_t>(samples), 0.0);
  for (const RoomSource& source : sources) {
    auto h = ImpulseResponses(room, beta, source.position_m, sensors_m, sample_rate_hz, 0.0);
    if (!h.ok()) return h.status();
    const size_t taps = h->front().size();
    const size_t used = std::min(source.signal.size(), static_cast<size_t>(samples));
    const int n = NextFastFftSize(static_cast<int>(used + taps));
    const int bins = n / 2 + 1;
    FftwFloats time = AllocateFftwFloats(static_cast<size_t>(n)),
               spectrum = AllocateFftwFloats(2 * static_cast<size_t>(bins)),
               filter = AllocateFftwFloats(2 * static_cast<size_t>(bins));
    FftwPlan forward = PlanRealForward(n, time.get(), spectrum.get(), FFTW_ESTIMATE);
    FftwPlan inverse = PlanRealInverse(n, spectrum.get(), time.get(), FFTW_ESTIMATE);
    if (!forward || !inverse) return Internal("FFTW could not plan a transform of " + std::to_string(n));
    std::vector<std::complex<float>> signal_spectrum(static_cast<size_t>(bins));
    std::fill(time.get(), time.get() + n, 0.0f);
    for (size_t i = 0; i < used; ++i) time[i] = static_cast<float>(source.signal[i]);
    fftwf_execute(forward.get());
    for (int k = 0; k < bins; ++k) signal_spectrum[static_cast<size_t>(k)] = {spectrum[2 * k], spectrum[2 * k + 1]};
    for (size_t m = 0; m < sensors_m.size(); ++m) {
      std::fill(time.get(), time.get() + n, 0.0f);
      for (size_t i = 0; i < taps; ++i) time[i] = static_cast<float>((*h)[m][i]);
      fftwf_execute_dft_r2c(forward.get(), time.get(), AsComplex(filter.get()));
      for (int k = 0; k < bins; ++k) {
        const std::complex<float> product =
            signal_spectrum[static_cast<size_t>(k)] * std::complex<float>(filter[2 * k], filter[2 * k + 1]);
        spectrum[2 * k] = product.real() / static_cast<float>(n);
        spectrum[2 * k + 1] = product.imag() / static_cast<float>(n);
      }
      fftwf_execute(inverse.get());
      double* channel = out.data() + m * static_cast<size_t>(samples);
      for (int64_t i = 0; i < samples && i < n; ++i) channel[i] += time[static_cast<size_t>(i)];
    }
  }
  return std::vector<float>(out.begin(), out.end());
}

}  // namespace localizer::engine
