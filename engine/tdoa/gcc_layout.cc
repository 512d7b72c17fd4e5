#include "engine/tdoa/gcc_layout.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>

#include "engine/tdoa/fftw_util.h"
#include "engine/tdoa/gcc_math.h"
#include "engine/tdoa/peak_interpolation.h"

namespace localizer::engine {
namespace {

std::string Value(double v) {
  char text[32];
  std::snprintf(text, sizeof text, "%g", v);
  return text;
}

// 1 / sqrt(n sum w^4 / (sum w^2)^2) over the frame's taper (gcc_layout.h); 1 for a rectangle.
float TaperNoiseFactor(int n, double taper_fraction) {
  double sum2 = 0.0, sum4 = 0.0;
  for (const float gain : TaperGains(n, taper_fraction)) {
    const double w2 = static_cast<double>(gain) * gain;
    sum2 += w2;
    sum4 += w2 * w2;
  }
  return sum4 > 0.0 ? static_cast<float>(sum2 / std::sqrt(n * sum4)) : 1.0f;
}

// sum w^2 t^2 / sum w^2 over the frame's taper w (gcc_layout.h), t seconds from its centre.
double WindowTimeVariance(int n, double taper_fraction, double sample_rate_hz) {
  const std::vector<float> gains = TaperGains(n, taper_fraction);
  double sum_w = 0.0, sum_wt2 = 0.0;
  const double centre = 0.5 * (n - 1);
  for (int i = 0; i < n; ++i) {
    const double gain = gains.empty() ? 1.0 : static_cast<double>(gains[static_cast<std::size_t>(i)]);
    const double w = gain * gain;
    const double t_s = (i - centre) / sample_rate_hz;
    sum_w += w;
    sum_wt2 += w * t_s * t_s;
  }
  return sum_w > 0.0 ? sum_wt2 / sum_w : 0.0;
}

}  // namespace

std::vector<float> TaperGains(int n, double taper_fraction) {
  const int edge = TaperEdgeSamples(n, static_cast<float>(taper_fraction));
  std::vector<float> gains;
  if (edge <= 0) return gains;
  gains.reserve(static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i) gains.push_back(TaperGain(i, n, edge));
  return gains;
}

int GccLayout::widest_lag() const {
  int widest = 0;
  for (int lag : max_lag_samples) widest = std::max(widest, lag);
  for (int lag : cross_max_lag_samples) widest = std::max(widest, lag);
  return widest;
}

StatusOr<GccLayout> ComputeGccLayout(const ArrayGeometry& array, const GccOptions& options) {
  LOCALIZER_RETURN_IF_ERROR(options.Validate());
  GccLayout layout;
  layout.frame_samples = options.frame_samples;
  layout.channels = array.sensor_count();
  const double fs = options.sample_rate_hz;
  // Lags the stage reads: the physical window plus the margin, plus the interpolator's reach.
  // In double: a physical delay or margin near INT_MAX must clamp, not overflow.
  const auto wanted_lag = [&](int pair) {
    return std::ceil(array.max_delay_s(pair) * fs) + options.lag_margin_samples;
  };
  double widest_wanted = 0.0;
  for (int p = 0; p < array.pair_count(); ++p) widest_wanted = std::max(widest_wanted, wanted_lag(p));
  // Zero padding to N >= frame + reach + 1 makes the circular correlation equal the linear one
  // at every lag |l| <= reach (the alias of lag l sits at l -/+ N, beyond the frame). Twice
  // the frame would also be linear at lags nobody reads, at twice the FFT cost.
  const double reach = std::min(widest_wanted, static_cast<double>(options.frame_samples)) + kPeakHalfWidth;
  layout.fft_size = NextFastFftSize(options.frame_samples + static_cast<int>(reach) + 1);
  layout.bin_count = layout.fft_size / 2 + 1;

  const double bins_per_hz = layout.fft_size / fs;
  layout.band_first_bin = static_cast<int>(std::ceil(options.band_low_hz * bins_per_hz));
  layout.band_end_bin = options.band_high_hz > 0.0
                            ? static_cast<int>(std::floor(options.band_high_hz * bins_per_hz)) + 1
                            : layout.bin_count;
  layout.band_end_bin = std::min(layout.band_end_bin, layout.bin_count);
  if (layout.band_first_bin >= layout.band_end_bin) {
    return InvalidArgument("band [" + Value(options.band_low_hz) + ", " + Value(options.band_high_hz) +
                           "] Hz holds no FFT bin (bin spacing " + Value(fs / layout.fft_size) + " Hz)");
  }
  layout.taper_noise_factor = TaperNoiseFactor(options.frame_samples, options.taper_fraction);
  layout.window_time_var_s2 = WindowTimeVariance(options.frame_samples, options.taper_fraction, options.sample_rate_hz);
  layout.noise_floor_inverse =
      layout.taper_noise_factor * static_cast<float>(std::sqrt(2.0 * (layout.band_end_bin - layout.band_first_bin)));

  // Keep each window and the interpolator's reach inside half the transform.
  const int half_fft = layout.fft_size / 2;  // an integer: the transform's half length
  const double lag_limit = half_fft - 1.0 - kPeakHalfWidth;
  for (int p = 0; p < array.pair_count(); ++p) {
    layout.max_lag_samples.push_back(static_cast<int>(std::min(wanted_lag(p), lag_limit)));
  }
  if (options.keep_gcc && array.sensor_count() <= options.cross_pairs_max_sensors) {
    const double alias_limit = layout.fft_size - options.frame_samples - kPeakHalfWidth - 1.0;
    const double c = array.sound_speed_mps();
    for (int a = 0; a < array.sensor_count(); ++a) {
      for (int b = a + 1; b < array.sensor_count(); ++b) {
        if (a == array.reference_sensor() || b == array.reference_sensor()) continue;
        const double wanted =
            std::ceil((array.sensor_m(a) - array.sensor_m(b)).norm() / c * fs) + options.lag_margin_samples;
        layout.cross_sensors.push_back({a, b});
        layout.cross_max_lag_samples.push_back(
            static_cast<int>(std::max(0.0, std::min({wanted, lag_limit, alias_limit}))));
      }
    }
  }
  return layout;
}

}  // namespace localizer::engine
