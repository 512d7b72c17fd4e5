#include "engine/doa/pair_spectra.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <numbers>
#include <span>
#include <string>

namespace localizer::engine {
namespace {
constexpr double kRelativeFloor = 1e-12;  // of the frame's mean power: a silent bin
// Each bin's share of signal (RemoveDelay; engine/tdoa/signal_share.h): its power averaged
// over the sensors and 9 neighbouring bins against the frame's floor. With signal weighting
// the share weighs the bins too, and a talker's harmonics lie 3-8 bins apart (90-250 Hz at
// 31 Hz per bin, 512 samples at 16 kHz): each bin's share reads its power averaged with one
// neighbour each side (against the floor of the wide average), and the flatness test the
// true upper quantile. Measured on seeded rooms against 9, 5 and 1 (ACCURACY.md, "A talker's
// harmonics").
SignalShareOptions ShareOptions(bool signal_weighting) {
  SignalShareOptions options;  // the weighting's
  if (!signal_weighting) {     // the removal's alone, as it was tuned
    options.share_window_bins = options.floor_window_bins;
    options.exact_upper_quantile = false;
  }
  return options;
}

// Floats per channel, rounded up so every channel starts SIMD-aligned (FFTW's new-array
// execute needs the alignment the plan was made with).
int Stride(int floats) { return (floats + 15) / 16 * 16; }

// Phasor chains over the in-band bins: lane j starts at bin first + j and is advanced by the
// rotation of kLanes bins. One chain is a serial dependency of complex products (and
// std::complex's product checks for infinities); kLanes chains in real arithmetic keep the
// vector units busy.
constexpr int kLanes = 8;  // StartPhasors fills exactly 8
// Lanes' starts e^(i a (first + j)) and the rotation e^(i a kLanes) (a: radians per bin),
// from two sincos: e^(i a first) and e^(i a), whose powers 2, 4 and 8 are products.
void StartPhasors(double a, int first, double* pr, double* pi, double* cr, double* ci) {
  const double r1 = std::cos(a), i1 = std::sin(a);
  const double r2 = r1 * r1 - i1 * i1, i2 = 2.0 * r1 * i1;
  const double r4 = r2 * r2 - i2 * i2, i4 = 2.0 * r2 * i2;
  pr[0] = std::cos(a * first);
  pi[0] = std::sin(a * first);
  pr[1] = pr[0] * r1 - pi[0] * i1;
  pi[1] = pr[0] * i1 + pi[0] * r1;
  for (int j = 2; j < 4; ++j) {
    pr[j] = pr[j - 2] * r2 - pi[j - 2] * i2;
    pi[j] = pr[j - 2] * i2 + pi[j - 2] * r2;
  }
  for (int j = 4; j < 8; ++j) {
    pr[j] = pr[j - 4] * r4 - pi[j - 4] * i4;
    pi[j] = pr[j - 4] * i4 + pi[j - 4] * r4;
  }
  *cr = r4 * r4 - i4 * i4;
  *ci = 2.0 * r4 * i4;
}
}  // namespace

StatusOr<PairSpectra> PairSpectra::Create(const PairSpectraOptions& o) {
  if (o.sensors < 2) return InvalidArgument("sensors must be at least 2");
  if (o.frame_samples < 16) return InvalidArgument("frame_samples must be at least 16");
  if (!(o.sample_rate_hz > 0.0) || !std::isfinite(o.sample_rate_hz))
    return InvalidArgument("sample_rate_hz must be positive and finite");
  const double nyquist_hz = 0.5 * o.sample_rate_hz;
  const double high_hz = o.band_high_hz > 0.0 ? o.band_high_hz : nyquist_hz;
  if (!(o.band_low_hz >= 0.0) || !(high_hz > o.band_low_hz) || high_hz > nyquist_hz)
    return InvalidArgument("band must satisfy 0 <= band_low_hz < band_high_hz <= sample_rate_hz / 2");
  if (o.max_lag_samples < 1) return InvalidArgument("max_lag_samples must be at least 1");
  if (o.rise_lag_frames < 1 || o.rise_lag_frames > 64) return InvalidArgument("rise_lag_frames must be in [1, 64]");

  PairSpectra s;
  s.options_ = o;
  s.share_finder_ = SignalShare(ShareOptions(o.signal_weighting));
  s.fft_size_ = NextFastFftSize(o.frame_samples + o.max_lag_samples + 1);
  if (2 * o.max_lag_samples + 1 > s.fft_size_ / 2)
    return InvalidArgument("the lag window (" + std::to_string(o.max_lag_samples) +
                           " samples either side) does not fit in half the transform; use longer frames");
  const int half = s.fft_size_ / 2;
  for (int k = 1; k < half; ++k) {
    const double f_hz = k * o.sample_rate_hz / s.fft_size_;
    if (f_hz >= o.band_low_hz && f_hz <= high_hz) s.bins_.push_back(k);
  }
  if (s.bins_.empty()) return InvalidArgument("the band holds no FFT bin");
  for (int k : s.bins_) {
    s.omega_.push_back(2.0 * std::numbers::pi / s.fft_size_ * k);
    s.omega_squared_.push_back(s.omega_.back() * s.omega_.back());
  }
  s.noise_sigma_ =
      std::sqrt(static_cast<double>(s.fft_size_) / o.frame_samples / (2.0 * static_cast<double>(s.bins_.size())));
  for (int i = 0; i < o.sensors; ++i)
    for (int j = i + 1; j < o.sensors; ++j) s.pairs_.emplace_back(i, j);
  s.g_.assign(s.pairs_.size(), std::vector<std::complex<double>>(s.bins_.size()));
  s.history_.assign(static_cast<size_t>(o.rise_lag_frames) + 1, s.g_);
  if (!o.diffuse_distance_m.empty()) {
    if (o.diffuse_distance_m.size() != s.pairs_.size() || !(o.sound_speed_mps > 0.0))
      return InvalidArgument("diffuse weighting needs one distance per pair and a positive sound speed");
    for (double d_m : o.diffuse_distance_m) {
      if (!(d_m > 0.0 && std::isfinite(d_m))) return InvalidArgument("a pair's distance must be positive and finite");
      std::vector<double> v;
      double sum_squares = 0.0;
      for (int k : s.bins_) {
        const double x = 2.0 * std::numbers::pi * (k * o.sample_rate_hz / s.fft_size_) * d_m / o.sound_speed_mps;
        const double gamma = std::sin(x) / x;
        v.push_back(1.0 - gamma * gamma);
        sum_squares += v.back() * v.back();
      }
      if (!(sum_squares > 0.0)) return InvalidArgument("diffuse weighting leaves no bin in the band");
      const double scale = std::sqrt(static_cast<double>(v.size()) / sum_squares);
      for (double& w : v) w *= scale;
      s.diffuse_weight_.push_back(std::move(v));
    }
  }

  const int spectrum_stride = Stride(2 * (half + 1));
  // One more channel slot than sensors: the partner of a channel transformed alone.
  s.spectra_ = AllocateFftwFloats(static_cast<size_t>(spectrum_stride) * (o.sensors + 1));
  s.cross_ = AllocateFftwFloats(static_cast<size_t>(spectrum_stride));
  s.cross_b_ = AllocateFftwFloats(static_cast<size_t>(spectrum_stride));
  if (!s.packed_.Init(s.fft_size_, s.bins_.front(), s.bins_.back() + 1, FFTW_ESTIMATE))
    return Internal("FFTW could not plan a transform of " + std::to_string(s.fft_size_));
  return s;
}

void PairSpectra::FindSignalShare() {
  share_ready_ = true;
  const size_t n = bins_.size();
  const bool flat = share_finder_.Find(bin_power_);
  const std::span<const double> signal_share = share_finder_.shares();
  share_norm_ = 0.0;
  for (size_t b = 0; b < n; ++b) share_norm_ += signal_share[b] * signal_share[b];
  // With signal weighting, the weight each pair's bins get this frame: share times the
  // diffuse weight, rescaled to sum_k weight^2 = B (a flat frame: the diffuse weight, or 1).
  const size_t pairs = pairs_.size();
  if (options_.signal_weighting) {
    applied_weight_.resize(pairs * n);
    for (size_t p = 0; p < pairs; ++p) {
      const double* v = diffuse_weight_.empty() ? nullptr : diffuse_weight_[p].data();
      double* a = applied_weight_.data() + p * n;
      double sum_squares = 0.0;
      for (size_t k = 0; k < n; ++k) {
        a[k] = signal_share[k] * (v ? v[k] : 1.0);  // a flat frame's shares are all 1
        sum_squares += a[k] * a[k];
      }
      if (flat) continue;          // exactly the weights without signal weighting
      if (!(sum_squares > 0.0)) {  // no bin holds signal on this pair: weighted as a flat frame
        for (size_t k = 0; k < n; ++k) a[k] = v ? v[k] : 1.0;
        continue;
      }
      const double scale = std::sqrt(static_cast<double>(n) / sum_squares);
      for (size_t k = 0; k < n; ++k) a[k] *= scale;
    }
  }
  // With diffuse or signal weighting, each pair's model weights (the share times the bin's
  // weight) and their norm, once a frame (RemoveDelay runs per pair for every source found
  // and re-estimated).
  const bool weighted = options_.signal_weighting || !diffuse_weight_.empty();
  model_weight_.resize(weighted ? pairs * n : 0);
  model_norm_.assign(weighted ? pairs : 0, 0.0);
  for (size_t p = 0; p < model_norm_.size(); ++p) {
    const double* v = options_.signal_weighting ? applied_weight_.data() + p * n : diffuse_weight_[p].data();
    double* w = model_weight_.data() + p * n;
    double norm = 0.0;
    for (size_t k = 0; k < n; ++k) {
      w[k] = signal_share[k] * v[k];
      norm += w[k] * w[k];
    }
    model_norm_[p] = norm;
  }
}

Status PairSpectra::Analyse(const float* frame, Measurement* field) {
  const int n = options_.frame_samples, half = fft_size_ / 2;
  const int spectrum_stride = Stride(2 * (half + 1));
  const auto spectrum = [&](int c) { return spectra_.get() + static_cast<size_t>(c) * spectrum_stride; };
  // Sensor c's samples into part `part` (0: real, 1: imaginary) of the packed transform's
  // input; false when one is not finite.
  const auto load = [&](int c, int part) {
    const float* in = frame + static_cast<size_t>(c) * n;
    float* t = packed_.forward_input() + part;
    uint32_t non_finite = 0;  // an all-ones exponent: inf or NaN (integer ops, so the loop vectorises)
    for (int i = 0; i < n; ++i) {
      t[2 * i] = in[i];
      non_finite |= static_cast<uint32_t>((std::bit_cast<uint32_t>(in[i]) & 0x7f800000u) == 0x7f800000u);
    }
    return non_finite == 0;
  };
  // Sensors c and c + 1 through one transform (its zero-padded tail stays zero: the transform
  // preserves its input); a last sensor alone with a zero imaginary part.
  for (int c = 0; c < options_.sensors; c += 2) {
    const bool two = c + 1 < options_.sensors;
    if (!load(c, 0)) return InvalidArgument("sensor " + std::to_string(c) + " has a non-finite sample");
    if (two && !load(c + 1, 1)) return InvalidArgument("sensor " + std::to_string(c + 1) + " has a non-finite sample");
    if (!two) {
      for (int i = 0; i < n; ++i) packed_.forward_input()[2 * i + 1] = 0.0f;
    }
    packed_.Forward(spectrum(c), spectrum(two ? c + 1 : options_.sensors));
  }
  // The in-band bins of every channel as doubles (re, im apart), their powers summed over
  // the channels (FindSignalShare) and the band's mean power, in one pass.
  const size_t nb = bins_.size(), first = static_cast<size_t>(bins_.front());  // consecutive bins
  bin_re_.resize(static_cast<size_t>(options_.sensors) * nb);
  bin_im_.resize(bin_re_.size());
  bin_power_.assign(nb, 0.0);
  double mean_power = 0.0;
  for (int c = 0; c < options_.sensors; ++c) {
    const float* x = spectra_.get() + static_cast<size_t>(c) * spectrum_stride + 2 * first;
    double* re = bin_re_.data() + static_cast<size_t>(c) * nb;
    double* im = bin_im_.data() + static_cast<size_t>(c) * nb;
    for (size_t b = 0; b < nb; ++b) {
      re[b] = x[2 * b];
      im[b] = x[2 * b + 1];
      const double power = re[b] * re[b] + im[b] * im[b];  // float products: exact in double
      mean_power += power;
      bin_power_[b] += power;
    }
  }
  mean_power /= static_cast<double>(options_.sensors) * static_cast<double>(nb);
  band_power_ = mean_power;
  const double floor = kRelativeFloor * mean_power;
  share_ready_ = false;                              // RemoveDelay finds the signal share when a frame needs it
  if (options_.signal_weighting) FindSignalShare();  // every frame: the bins' weights

  field->sample_rate_hz = options_.sample_rate_hz;
  field->pairs.resize(pairs_.size());
  newest_ = (newest_ + 1) % history_.size();  // overwrites the oldest whole spectrum
  for (size_t p = 0; p < pairs_.size(); ++p) {
    const double* ar = bin_re_.data() + static_cast<size_t>(pairs_[p].first) * nb;
    const double* ai = bin_im_.data() + static_cast<size_t>(pairs_[p].first) * nb;
    const double* br = bin_re_.data() + static_cast<size_t>(pairs_[p].second) * nb;
    const double* bi = bin_im_.data() + static_cast<size_t>(pairs_[p].second) * nb;
    double* g = reinterpret_cast<double*>(g_[p].data());  // (re, im) pairs
    const double* v = options_.signal_weighting ? applied_weight_.data() + p * nb
                      : diffuse_weight_.empty() ? nullptr
                                                : diffuse_weight_[p].data();
    for (size_t b = 0; b < nb; ++b) {
      // X_i conj(X_j) / |X_i conj(X_j)|, 0 where either channel is silent. The products of
      // floats are exact in double, so the sums are rounded once.
      const double cr = ar[b] * br[b] + ai[b] * bi[b], ci = ai[b] * br[b] - ar[b] * bi[b];
      const double magnitude = std::sqrt(cr * cr + ci * ci);  // std::abs calls hypot: 3x slower here
      const bool kept = magnitude > floor && magnitude > 0.0;
      const double weight = v ? v[b] : 1.0;  // diffuse or signal weighting (1: exact, as without)
      g[2 * b] = kept ? cr / magnitude * weight : 0.0;
      g[2 * b + 1] = kept ? ci / magnitude * weight : 0.0;
    }
    history_[newest_][p] = g_[p];
  }
  FillFields(field);
  ++frames_analysed_;
  return Status::Ok();
}

void PairSpectra::FillTwoFields(int p, int q, Measurement* field) {
  // Each pair's in-band bins as floats; the packed inverse reads no others.
  const auto load = [&](int pair, float* cross) {
    const std::vector<std::complex<double>>& g = g_[static_cast<size_t>(pair)];
    for (size_t b = 0; b < bins_.size(); ++b) {
      cross[2 * static_cast<size_t>(bins_[b])] = static_cast<float>(g[b].real());
      cross[2 * static_cast<size_t>(bins_[b]) + 1] = static_cast<float>(g[b].imag());
    }
  };
  load(p, cross_.get());
  if (q >= 0) load(q, cross_b_.get());
  packed_.Inverse(cross_.get(), q >= 0 ? cross_b_.get() : nullptr);
  FillField(p, packed_.inverse_output(), &field->pairs[static_cast<size_t>(p)]);
  if (q >= 0) FillField(q, packed_.inverse_output() + 1, &field->pairs[static_cast<size_t>(q)]);
}

// correlation: the pair's inverse transform, lag l at correlation[2 (l mod M)].
void PairSpectra::FillField(int p, const float* correlation, PairMeasurement* out) {
  const int m = fft_size_, max_lag = options_.max_lag_samples;
  const double scale = 1.0 / (2.0 * static_cast<double>(bins_.size()));  // the inverse's output is 2 B R
  out->sensor = pairs_[static_cast<size_t>(p)].second;
  out->first_lag_samples = -max_lag;
  const int window = 2 * max_lag + 1;
  out->gcc.resize(static_cast<size_t>(window));
  for (int i = 0; i < window; ++i) {
    const int wrapped = (i - max_lag + m) % m;  // lag i - max_lag, modulo the transform
    out->gcc[static_cast<size_t>(i)] = static_cast<float>(correlation[2 * static_cast<size_t>(wrapped)] * scale);
  }
  out->peak_value = noise_sigma_;
  out->peak_snr = 1.0;
}

void PairSpectra::Phasors(double lag_samples) {
  // e^(i step (first + b) l) for every in-band bin b, over kLanes chains.
  const double step = 2.0 * std::numbers::pi / fft_size_;
  const auto n = static_cast<int>(bins_.size());
  phasor_re_.resize(static_cast<size_t>(n));
  phasor_im_.resize(static_cast<size_t>(n));
  double pr[kLanes], pi[kLanes], cr = 0.0, ci = 0.0;
  StartPhasors(step * lag_samples, bins_.front(), pr, pi, &cr, &ci);  // the in-band bins are consecutive
  double* re = phasor_re_.data();
  double* im = phasor_im_.data();
  int b = 0;
  for (; b + kLanes <= n; b += kLanes) {
    for (int j = 0; j < kLanes; ++j) {
      re[b + j] = pr[j];
      im[b + j] = pi[j];
      const double next_r = pr[j] * cr - pi[j] * ci;
      pi[j] = pr[j] * ci + pi[j] * cr;
      pr[j] = next_r;
    }
  }
  for (int j = 0; b < n; ++b, ++j) {  // the last < kLanes bins: lane j holds bin b's phasor
    re[b] = pr[j];
    im[b] = pi[j];
  }
}

void PairSpectra::RemoveDelay(int p, double lag_samples, std::vector<std::complex<double>>* taken) {
  std::vector<std::complex<double>>& g = g_[static_cast<size_t>(p)];
  if (!share_ready_) FindSignalShare();
  // The weighted least-squares pure delay: c minimising sum_k |G_p(k) - c w_k e^(-i w k l)|^2,
  // w_k the bin's share of signal (FindSignalShare), subtracted with those weights. One pass
  // over kLanes phasor chains sums c's numerator and keeps the phasors for the subtraction.
  const double step = 2.0 * std::numbers::pi / fft_size_;
  const auto n = static_cast<int>(g.size());
  phasor_re_.resize(static_cast<size_t>(n));
  phasor_im_.resize(static_cast<size_t>(n));
  double pr[kLanes], pi[kLanes], rr = 0.0, ri = 0.0, ar[kLanes] = {}, ai[kLanes] = {};
  StartPhasors(step * lag_samples, bins_.front(), pr, pi, &rr, &ri);
  const double* gv = reinterpret_cast<const double*>(g.data());  // (re, im) pairs
  // The model's bins carry the pair's diffuse or signal weights too (FindSignalShare).
  const bool weighted = !model_norm_.empty();
  const double* w = weighted ? model_weight_.data() + static_cast<size_t>(p) * g.size() : share_finder_.shares().data();
  double norm = weighted ? model_norm_[static_cast<size_t>(p)] : share_norm_;
  double* re = phasor_re_.data();
  double* im = phasor_im_.data();
  int b = 0;
  for (; b + kLanes <= n; b += kLanes) {
    for (int j = 0; j < kLanes; ++j) {
      const double gr = gv[2 * (b + j)], gi = gv[2 * (b + j) + 1];
      re[b + j] = pr[j];
      im[b + j] = pi[j];
      ar[j] += w[b + j] * (gr * pr[j] - gi * pi[j]);
      ai[j] += w[b + j] * (gr * pi[j] + gi * pr[j]);
      const double next_r = pr[j] * rr - pi[j] * ri;
      pi[j] = pr[j] * ri + pi[j] * rr;
      pr[j] = next_r;
    }
  }
  for (int j = 0; b < n; ++b, ++j) {  // the last < kLanes bins: lane j holds bin b's phasor
    const double gr = gv[2 * b], gi = gv[2 * b + 1];
    re[b] = pr[j];
    im[b] = pi[j];
    ar[j] += w[b] * (gr * pr[j] - gi * pi[j]);
    ai[j] += w[b] * (gr * pi[j] + gi * pr[j]);
  }
  double sum_r = 0.0, sum_i = 0.0;
  for (int j = 0; j < kLanes; ++j) {
    sum_r += ar[j];
    sum_i += ai[j];
  }
  norm = std::max(norm, 1e-12);
  const double cr = sum_r / norm, ci = sum_i / norm;
  taken->resize(static_cast<size_t>(n));  // allocates only the first time a vector is used
  double* tv = reinterpret_cast<double*>(taken->data());
  double* gw = reinterpret_cast<double*>(g.data());
  for (b = 0; b < n; ++b) {  // G -= c w_k conj(phasor)
    const double tr = cr * w[b], ti = ci * w[b];
    tv[2 * b] = tr;
    tv[2 * b + 1] = ti;
    gw[2 * b] -= tr * re[b] + ti * im[b];
    gw[2 * b + 1] -= ti * re[b] - tr * im[b];
  }
}

void PairSpectra::FillFields(Measurement* field) {
  const auto pairs = static_cast<int>(pairs_.size());
  for (int p = 0; p < pairs; p += 2) FillTwoFields(p, p + 1 < pairs ? p + 1 : -1, field);
}

void PairSpectra::RestoreDelay(int p, double lag_samples, const std::vector<std::complex<double>>& taken) {
  std::vector<std::complex<double>>& g = g_[static_cast<size_t>(p)];
  Phasors(lag_samples);
  const size_t n = std::min(g.size(), taken.size());
  const double* tv = reinterpret_cast<const double*>(taken.data());
  double* gw = reinterpret_cast<double*>(g.data());
  const double* re = phasor_re_.data();
  const double* im = phasor_im_.data();
  for (size_t b = 0; b < n; ++b) {  // G += taken conj(phasor)
    const double tr = tv[2 * b], ti = tv[2 * b + 1];
    gw[2 * b] += tr * re[b] + ti * im[b];
    gw[2 * b + 1] += ti * re[b] - tr * im[b];
  }
}

void PairSpectra::ResetToWhole() {
  if (frames_analysed_ == 0) return;
  const std::vector<std::vector<std::complex<double>>>& whole = history_[newest_];
  for (size_t p = 0; p < g_.size(); ++p) std::copy(whole[p].begin(), whole[p].end(), g_[p].begin());
}

double PairSpectra::WholeAt(int p, double lag_samples, bool previous) const {
  const size_t back = previous ? history_.size() - 1 : 0;
  if (frames_analysed_ <= static_cast<int64_t>(back)) return 0.0;
  return Evaluate<false>(history_[(newest_ + history_.size() - back) % history_.size()][static_cast<size_t>(p)],
                         lag_samples)
      .r;
}

PairSpectra::Value PairSpectra::WholeValueAt(int p, double lag_samples) const {
  if (frames_analysed_ == 0) return Value{};
  return Evaluate(history_[newest_][static_cast<size_t>(p)], lag_samples);
}

PairSpectra::Value PairSpectra::At(int p, double lag_samples) const {
  return Evaluate(g_[static_cast<size_t>(p)], lag_samples);
}

template <bool kDerivatives>
PairSpectra::Value PairSpectra::Evaluate(const std::vector<std::complex<double>>& g, double lag_samples) const {
  // sum_b G(b) exp(i w_b l), w_b = step (first + b), over kLanes phasor chains.
  const double step = 2.0 * std::numbers::pi / fft_size_;  // radians per bin per sample of lag
  const auto n = static_cast<int>(g.size());
  double pr[kLanes], pi[kLanes], cr = 0.0, ci = 0.0, r[kLanes] = {}, dr[kLanes] = {}, d2r[kLanes] = {};
  StartPhasors(step * lag_samples, bins_.front(), pr, pi, &cr, &ci);  // the in-band bins are consecutive
  const double* gv = reinterpret_cast<const double*>(g.data());       // (re, im) pairs
  const double* w = omega_.data();
  const double* w2 = omega_squared_.data();
  int b = 0;
  for (; b + kLanes <= n; b += kLanes) {
    for (int j = 0; j < kLanes; ++j) {
      const double gr = gv[2 * (b + j)], gi = gv[2 * (b + j) + 1];
      const double tr = gr * pr[j] - gi * pi[j], ti = gr * pi[j] + gi * pr[j];
      r[j] += tr;
      if constexpr (kDerivatives) {
        dr[j] -= w[b + j] * ti;
        d2r[j] -= w2[b + j] * tr;
      }
      const double next_r = pr[j] * cr - pi[j] * ci;
      pi[j] = pr[j] * ci + pi[j] * cr;
      pr[j] = next_r;
    }
  }
  for (int j = 0; b < n; ++b, ++j) {  // the last < kLanes bins: lane j holds bin b's phasor
    const double gr = gv[2 * b], gi = gv[2 * b + 1];
    const double tr = gr * pr[j] - gi * pi[j], ti = gr * pi[j] + gi * pr[j];
    r[j] += tr;
    if constexpr (kDerivatives) {
      dr[j] -= w[b] * ti;
      d2r[j] -= w2[b] * tr;
    }
  }
  Value v;
  const double inv_b = 1.0 / static_cast<double>(n);
  for (int j = 0; j < kLanes; ++j) {
    v.r += r[j] * inv_b;
    v.dr += dr[j] * inv_b;
    v.d2r += d2r[j] * inv_b;
  }
  return v;
}

}  // namespace localizer::engine
