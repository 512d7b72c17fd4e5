#include "engine/doa/echo_test.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>

namespace localizer::engine {

Status EchoTestOptions::Validate() const {
  if (!(sample_rate_hz > 0.0) || !std::isfinite(sample_rate_hz))
    return InvalidArgument("sample_rate_hz must be positive and finite");
  if (!(sound_speed_mps > 0.0) || !std::isfinite(sound_speed_mps))
    return InvalidArgument("sound_speed_mps must be positive and finite");
  if (frame_samples < 16 || frame_samples > kMaxFrameSamples)
    return InvalidArgument("frame_samples must be in [16, " + std::to_string(kMaxFrameSamples) +
                           "] for the echo test (its spectra are kept per sensor)");
  const double nyquist_hz = 0.5 * sample_rate_hz;
  const double high_hz = band_high_hz > 0.0 ? band_high_hz : nyquist_hz;
  if (!(band_low_hz >= 0.0) || !(high_hz > band_low_hz) || high_hz > nyquist_hz)
    return InvalidArgument("band must satisfy 0 <= band_low_hz < band_high_hz <= sample_rate_hz / 2");
  if (!(max_delay_s > 0.0) || !std::isfinite(max_delay_s)) return InvalidArgument("max_delay_s must be positive");
  if (!(max_leakage > 0.0 && max_leakage < 1.0)) return InvalidArgument("max_leakage must be in (0, 1)");
  if (!(min_selective_share >= 0.0 && min_selective_share <= 1.0))
    return InvalidArgument("min_selective_share must be in [0, 1]");
  return Status::Ok();
}

StatusOr<EchoTest> EchoTest::Create(const std::vector<Vec3>& sensors_m, const EchoTestOptions& options) {
  LOCALIZER_RETURN_IF_ERROR(options.Validate());
  if (sensors_m.size() < 2) return InvalidArgument("an echo test needs at least 2 sensors");
  EchoTest t;
  t.options_ = options;
  Vec3 centroid = Vec3::Zero();
  for (const Vec3& s : sensors_m) centroid += s;
  centroid /= static_cast<double>(sensors_m.size());
  for (const Vec3& s : sensors_m) t.sensors_m_.push_back(s - centroid);
  t.max_lag_ = std::max(1, std::min(static_cast<int>(std::lround(options.max_delay_s * options.sample_rate_hz)),
                                    options.frame_samples / 2));
  t.fft_size_ = NextFastFftSize(options.frame_samples + t.max_lag_ + 1);
  const int m = t.fft_size_, half = m / 2;
  const double high_hz = options.band_high_hz > 0.0 ? options.band_high_hz : 0.5 * options.sample_rate_hz;
  t.first_bin_ = std::max(1, static_cast<int>(std::ceil(options.band_low_hz * m / options.sample_rate_hz)));
  t.end_bin_ = std::min(half, static_cast<int>(std::floor(high_hz * m / options.sample_rate_hz)) + 1);
  if (t.end_bin_ <= t.first_bin_) return InvalidArgument("the band holds no FFT bin");
  t.spectrum_stride_ = 2 * (half + 1);
  // One more channel slot than sensors: the partner of a channel transformed alone.
  t.spectra_ = AllocateFftwFloats(static_cast<size_t>(t.spectrum_stride_) * (sensors_m.size() + 1));
  t.cross_ = AllocateFftwFloats(static_cast<size_t>(t.spectrum_stride_));
  if (!t.packed_.Init(m, t.first_bin_, t.end_bin_, FFTW_ESTIMATE))
    return Internal("FFTW could not plan a transform of " + std::to_string(m));
  return t;
}

void EchoTest::Load(const float* frame) {
  // Two channels per complex transform (packed_transforms.h); only the band's bins are read.
  const int n = options_.frame_samples, sensors = static_cast<int>(sensors_m_.size());
  const auto spectrum = [&](int c) { return spectra_.get() + static_cast<size_t>(c) * spectrum_stride_; };
  float* in = packed_.forward_input();  // its zero-padded tail stays zero
  for (int c = 0; c < sensors; c += 2) {
    const bool two = c + 1 < sensors;
    const float* a = frame + static_cast<size_t>(c) * n;
    for (int i = 0; i < n; ++i) {
      in[2 * i] = a[i];
      in[2 * i + 1] = two ? a[n + i] : 0.0f;
    }
    packed_.Forward(spectrum(c), spectrum(two ? c + 1 : sensors));
  }
}

bool EchoTest::Compare(const Vec3& u_i, const Vec3& u_j, EchoEvidence* out) {
  const size_t sensors = sensors_m_.size();
  const double samples_per_m = options_.sample_rate_hz / options_.sound_speed_mps;
  delay_i_.resize(sensors);
  delay_j_.resize(sensors);
  double spread = 0.0;
  for (size_t c = 0; c < sensors; ++c) {
    // A plane wave from u reaches sensor c at -(m_c . u) / c after the centroid.
    delay_i_[c] = -sensors_m_[c].dot(u_i) * samples_per_m;
    delay_j_[c] = -sensors_m_[c].dot(u_j) * samples_per_m;
    spread = std::max(spread, std::abs(delay_i_[c] - delay_j_[c]));
  }
  const int m = fft_size_;
  const double step = 2.0 * std::numbers::pi / m;
  // Each sensor's steering phasors exp(i w_k t) for both directions, advanced bin by bin by
  // the rotation exp(i step t) (double precision: 1e-13 after thousands of bins).
  phasors_.resize(8 * sensors);
  double* pir = phasors_.data();
  double* pii = pir + sensors;
  double* pjr = pii + sensors;
  double* pji = pjr + sensors;
  double* rir = pji + sensors;
  double* rii = rir + sensors;
  double* rjr = rii + sensors;
  double* rji = rjr + sensors;
  for (size_t c = 0; c < sensors; ++c) {
    pir[c] = std::cos(step * first_bin_ * delay_i_[c]);
    pii[c] = std::sin(step * first_bin_ * delay_i_[c]);
    pjr[c] = std::cos(step * first_bin_ * delay_j_[c]);
    pji[c] = std::sin(step * first_bin_ * delay_j_[c]);
    rir[c] = std::cos(step * delay_i_[c]);
    rii[c] = std::sin(step * delay_i_[c]);
    rjr[c] = std::cos(step * delay_j_[c]);
    rji[c] = std::sin(step * delay_j_[c]);
  }
  float* cross = cross_.get();
  std::fill(cross, cross + spectrum_stride_, 0.0f);
  double power_i = 0.0, power_j = 0.0;
  band_i_.clear();
  band_j_.clear();
  for (int k = first_bin_; k < end_bin_; ++k) {
    double bir = 0.0, bii = 0.0, bjr = 0.0, bji = 0.0, lr = 0.0, li = 0.0;
    for (size_t c = 0; c < sensors; ++c) {
      const float* x = spectra_.get() + c * static_cast<size_t>(spectrum_stride_) + 2 * static_cast<size_t>(k);
      const double xr = x[0], xi = x[1];
      const double ci = pir[c], si = pii[c], cj = pjr[c], sj = pji[c];
      bir += xr * ci - xi * si;
      bii += xr * si + xi * ci;
      bjr += xr * cj - xi * sj;
      bji += xr * sj + xi * cj;
      lr += ci * cj + si * sj;  // exp(i w (t_i - t_j))
      li += si * cj - ci * sj;
      pir[c] = ci * rir[c] - si * rii[c];
      pii[c] = ci * rii[c] + si * rir[c];
      pjr[c] = cj * rjr[c] - sj * rji[c];
      pji[c] = cj * rji[c] + sj * rjr[c];
    }
    const double leakage = std::hypot(lr, li) / static_cast<double>(sensors);
    if (!(leakage < options_.max_leakage)) continue;
    band_i_.push_back(bir * bir + bii * bii);
    band_j_.push_back(bjr * bjr + bji * bji);
    cross[2 * k] = static_cast<float>(bir * bjr + bii * bji);  // B_i conj(B_j)
    cross[2 * k + 1] = static_cast<float>(bii * bjr - bir * bji);
    power_i += band_i_.back();
    power_j += band_j_.back();
  }
  const size_t selective = band_i_.size();
  if (selective == 0 || selective < options_.min_selective_share * (end_bin_ - first_bin_) || !(power_i > 0.0) ||
      !(power_j > 0.0))
    return false;
  packed_.Inverse(cross, nullptr);  // correlation at [2n] = 2 Re sum_k C_k exp(i 2 pi k n / M)
  const double norm = 1.0 / (2.0 * std::sqrt(power_i * power_j));
  const float* out_r = packed_.inverse_output();
  const auto r = [&](int lag) { return out_r[2 * static_cast<size_t>(lag)]; };
  out->min_lag = std::min(max_lag_ + 1, static_cast<int>(std::ceil(spread)) + 2);
  out->lagging.assign(static_cast<size_t>(max_lag_), 0.0);
  out->leading.assign(static_cast<size_t>(max_lag_), 0.0);
  for (int tau = out->min_lag; tau <= max_lag_; ++tau) {
    out->lagging[static_cast<size_t>(tau - 1)] = r(m - tau) * norm;
    out->leading[static_cast<size_t>(tau - 1)] = r(tau) * norm;
  }
  out->power_i = power_i;
  out->power_j = power_j;
  for (int b = 0; b < EchoEvidence::kSubBands; ++b) {
    const size_t lo = band_i_.size() * b / EchoEvidence::kSubBands,
                 hi = band_i_.size() * (b + 1) / EchoEvidence::kSubBands;
    out->band_power_i[b] = out->band_power_j[b] = 0.0;
    for (size_t q = lo; q < hi; ++q) out->band_power_i[b] += band_i_[q], out->band_power_j[b] += band_j_[q];
  }
  return true;
}

}  // namespace localizer::engine
