// Generalised cross-correlation TDOA estimation (Knapp & Carter 1976) with FFTW3, float.
//
// For the reference channel x_r and channel x_k, both zero padded to N >= 2 * frame (so the
// correlation is linear, not circular), with spectra X_r, X_k:
//     G(f)   = X_k(f) conj(X_r(f)) * W(f) * B(f)
//     R(tau) = IFFT(G)(tau)            peaks at tau = delay (x_k(t) = x_r(t - delay))
// Weightings W(f):
//     PHAT       1 / |X_k X_r*|                   (default; whitens, sharp peak)
//     PHAT-beta  1 / |X_k X_r*|^beta               (beta in [0, 1]; 1 = PHAT, 0 = CC)
//     SCOT       1 / sqrt(|X_k|^2 |X_r|^2)  computed per frame (no averaging)
//     CC         1                                (plain cross-correlation)
// B(f) is 1 inside the optional band [band_low_hz, band_high_hz] and 0 outside.
// A small floor (1e-12 of the frame's mean power) keeps silent bins finite.
//
// The peak is searched only over |lag| <= max_delay_s(pair) * fs + lag_margin_samples and
// refined to a sub-sample lag (see peak_interpolation.h for the method and its measured
// bias). Quality = peak / largest |R| outside the main lobe within the window.
//
// Cost per frame: (channels) real FFTs of N plus (channels - 1) inverse FFTs of N, O(N) for
// the spectra; plans are made once in Create and reused, so Estimate allocates nothing
// after the first call.
#pragma once

#include <memory>
#include <string>

#include "engine/array/array_geometry.h"
#include "engine/tdoa/tdoa_estimator.h"

namespace localizer::engine {

enum class Weighting { kPhat, kPhatBeta, kScot, kCc };

// Parses "phat", "phat-beta", "scot", "cc".
StatusOr<Weighting> ParseWeighting(const std::string& name);
const char* WeightingName(Weighting w);

struct GccOptions {
  int frame_samples = 4096;       // samples per channel per frame, >= 64
  double sample_rate_hz = 0.0;    // > 0
  Weighting weighting = Weighting::kPhat;
  double phat_beta = 0.8;         // only for kPhatBeta, in [0, 1]
  double band_low_hz = 0.0;       // 0: from DC
  double band_high_hz = 0.0;      // 0: up to Nyquist
  int lag_margin_samples = 2;     // searched beyond the physical maximum delay, >= 0
  bool keep_gcc = true;           // copy the GCC over the lag window into the Measurement

  // OK, or INVALID_ARGUMENT naming the field and value.
  Status Validate() const;
};

class GccPhatEstimator final : public TdoaEstimator {
 public:
  static StatusOr<std::unique_ptr<GccPhatEstimator>> Create(const ArrayGeometry& array,
                                                            const GccOptions& options);
  ~GccPhatEstimator() override;
  GccPhatEstimator(const GccPhatEstimator&) = delete;
  GccPhatEstimator& operator=(const GccPhatEstimator&) = delete;

  Status Estimate(const float* frame, int frame_samples, double t_s, Measurement* out) override;

  const GccOptions& options() const;
  int fft_size() const;

 private:
  struct Impl;
  explicit GccPhatEstimator(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace localizer::engine
