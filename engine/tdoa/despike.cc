#include "engine/tdoa/despike.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>

namespace localizer::engine {

Status DespikeOptions::Validate() const {
  if (despike_k == 0.0) return Status::Ok();
  if (!(despike_k >= 1.0 && despike_k <= 1e6)) {
    char text[32];
    std::snprintf(text, sizeof text, "%g", despike_k);
    return InvalidArgument(std::string("DespikeOptions.despike_k is ") + text + "; must be 0 (off) or in [1, 1e6]");
  }
  if (coincidence_samples < 0 || coincidence_samples > (1 << 20)) {
    return InvalidArgument("DespikeOptions.coincidence_samples is " + std::to_string(coincidence_samples) +
                           "; must be in [0, 1048576]");
  }
  return Status::Ok();
}

namespace {

// The largest |x[i]| (0 for n = 0). A maximum is exact in any order, so 32 independent
// lanes (four 256-bit vectors) let the loads run ahead of the max's latency: one running
// maximum (what an `omp simd reduction(max)` compiled to) waited on it every vector, and the
// two scans over each channel cost about 4 % of the pipeline (BENCHMARKS.md, issue 20).
float LargestMagnitude(const float* x, int n) {
  constexpr int kMaxLanes = 32;
  float lanes[kMaxLanes] = {};
  int i = 0;
  for (; i + kMaxLanes <= n; i += kMaxLanes) {
#pragma omp simd
    for (int l = 0; l < kMaxLanes; ++l) lanes[l] = std::max(lanes[l], std::abs(x[i + l]));
  }
  float largest = 0.0f;
  for (; i < n; ++i) largest = std::max(largest, std::abs(x[i]));
  for (float lane : lanes) largest = std::max(largest, lane);
  return largest;
}

// The median of n >= 1 non-negative values to within max / 2^20 (max their largest): a
// bisection on the value whose counts are branch-free (they vectorise). std::nth_element on
// 256 values mispredicts about every other comparison and took 2-4 us per channel; this
// takes a fraction of that. The clip level needs the median to a few per cent; an impulse
// 1e4 x the median still leaves it to 1 %.
float ApproximateMedian(const float* values, int n) {
  float hi = LargestMagnitude(values, n);  // the values are magnitudes already
  float lo = 0.0f;
  const int half = (n + 1) / 2;  // the lower median's rank
  for (int iteration = 0; iteration < 20; ++iteration) {
    const float mid = 0.5f * (lo + hi);
    int at_most = 0;
#pragma omp simd reduction(+ : at_most)
    for (int i = 0; i < n; ++i) at_most += values[i] <= mid ? 1 : 0;
    if (at_most >= half) {
      hi = mid;
    } else {
      lo = mid;
    }
  }
  return hi;
}

Status CheckArguments(const DespikeOptions& options, const float* frame, int channels, int samples) {
  if (Status s = options.Validate(); !s.ok()) return s;
  if (frame == nullptr) return InvalidArgument("frame is null");
  if (channels < 1) return InvalidArgument("channels is " + std::to_string(channels) + "; must be >= 1");
  if (samples < 1) return InvalidArgument("samples is " + std::to_string(samples) + "; must be >= 1");
  return Status::Ok();
}

// Each channel's clip level into buffers.limits; true when some sample exceeds its channel's.
bool ClipLimits(const DespikeOptions& options, const float* frame, int channels, int samples, DespikeScratch& buffers) {
  std::vector<float>& magnitudes = buffers.magnitudes;
  magnitudes.resize(samples);
  constexpr float kMadToSigma = 1.4826f;
  constexpr int kMedianSamples = 256;  // the median to ~8 %: the clip level to ~0.4 sigma
  std::vector<float>& limits = buffers.limits;
  limits.assign(channels, 0.0f);
  for (int c = 0; c < channels; ++c) {
    const float* x = frame + static_cast<std::size_t>(c) * samples;
    // The median of |x| from at most kMedianSamples evenly spaced samples: a scale to set a
    // clip level by needs a few per cent, not the exact median, at a fraction of the cost.
    const int step = std::max(1, (samples + kMedianSamples - 1) / kMedianSamples);
    int n = 0;
    for (int i = 0; i < samples; i += step) magnitudes[static_cast<std::size_t>(n++)] = std::abs(x[i]);
    limits[c] = static_cast<float>(options.despike_k) * kMadToSigma * ApproximateMedian(magnitudes.data(), n);
  }
  // Most frames have nothing to clip: one vectorised pass per channel says so.
  for (int c = 0; c < channels; ++c) {
    const float peak = LargestMagnitude(frame + static_cast<std::size_t>(c) * samples, samples);
    if (limits[c] > 0.0f && peak > limits[c]) return true;
  }
  return false;
}

// Clips the outliers of a frame whose limits ClipLimits set; returns how many.
int ClipOutliers(const DespikeOptions& options, float* frame, int channels, int samples, DespikeScratch& buffers) {
  const std::vector<float>& limits = buffers.limits;
  const int window = options.coincidence_samples;
  const std::size_t stride = static_cast<std::size_t>(samples) + 1;
  if (window > 0) {
    buffers.outliers_before.resize(stride * channels);
    for (int c = 0; c < channels; ++c) {
      const float* x = frame + static_cast<std::size_t>(c) * samples;
      int* before = buffers.outliers_before.data() + stride * c;
      before[0] = 0;
      for (int i = 0; i < samples; ++i) before[i + 1] = before[i] + (std::abs(x[i]) > limits[c]);
    }
  }
  // Does channel c have an outlier in [i - window, i + window]?
  const auto outlier_near = [&](int c, int i) {
    const int* before = buffers.outliers_before.data() + stride * c;
    const int lo = std::max(0, i - window);
    const int hi = std::min(samples, i + window + 1);
    return before[hi] > before[lo];
  };
  const auto coincident = [&](int c, int i) {
    for (int other = 0; other < channels; ++other) {
      if (other != c && !outlier_near(other, i)) return false;
    }
    return true;
  };
  // Is the gate telling a source from noise on channel c? Independent impulses on the other
  // channels line up with one of c's by chance with probability
  //     chance = prod_o (1 - (1 - q_o)^(2 window + 1)),   q_o: channel o's share of outliers,
  // so about that share of c's outliers would be coincident without any source. A wide window
  // (a large array: 170 samples for 15 m of water at 16 kHz) or dense impulses make chance
  // near 1, and the gate then kept nearly every impulse. The gate is used only when clearly
  // more of c's outliers coincide than chance explains (a coherent source makes nearly all of
  // them coincide); otherwise every outlier of c is clipped, which costs a coherent source a
  // little distortion (tested: 0.25 sample) where keeping impulses costs whole frames.
  std::vector<char> gated(channels, 0);  // small, as limits
  if (window > 0 && channels > 1) {
    const double span = 2.0 * window + 1.0;
    for (int c = 0; c < channels; ++c) {
      double chance = 1.0;
      for (int o = 0; o < channels; ++o) {
        if (o == c) continue;
        const double share = static_cast<double>(buffers.outliers_before[stride * o + samples]) / samples;
        chance *= 1.0 - std::pow(1.0 - share, span);
      }
      const int outliers = buffers.outliers_before[stride * c + samples];
      if (outliers == 0) continue;
      const float* x = frame + static_cast<std::size_t>(c) * samples;
      int together = 0;
      for (int i = 0; i < samples; ++i) together += std::abs(x[i]) > limits[c] && coincident(c, i);
      // More than chance by three binomial standard deviations (the test's null: no source),
      // and a majority: where impulses outnumber the source, keeping them costs more.
      const double n = outliers;
      const double expected = chance * n + 3.0 * std::sqrt(n * chance * (1.0 - chance));
      gated[c] = together > std::max(0.5 * n, expected);
    }
  }
  int clipped = 0;
  for (int c = 0; c < channels; ++c) {
    float* x = frame + static_cast<std::size_t>(c) * samples;
    const float limit = limits[c];
    if (!(limit > 0.0f)) continue;  // a silent (or mostly zero) channel: nothing to scale by
    // Most channels have nothing to clip.
    if (!(LargestMagnitude(x, samples) > limit)) continue;
    for (int i = 0; i < samples; ++i) {
      const float v = x[i];
      if (!(std::abs(v) > limit)) continue;
      if (gated[c] && coincident(c, i)) continue;  // coherent across the array: the source, kept
      x[i] = std::clamp(v, -limit, limit);
      ++clipped;
    }
  }
  return clipped;
}

}  // namespace

Status Despike(const DespikeOptions& options, float* frame, int channels, int samples, DespikeScratch* scratch,
               DespikeStats* stats) {
  LOCALIZER_RETURN_IF_ERROR(CheckArguments(options, frame, channels, samples));
  if (stats != nullptr) stats->clipped_samples = 0;
  if (options.despike_k == 0.0) return Status::Ok();
  DespikeScratch local;
  DespikeScratch& buffers = scratch != nullptr ? *scratch : local;
  if (!ClipLimits(options, frame, channels, samples, buffers)) return Status::Ok();
  const int clipped = ClipOutliers(options, frame, channels, samples, buffers);
  if (stats != nullptr) stats->clipped_samples = clipped;
  return Status::Ok();
}

StatusOr<const float*> DespikedFrame(const DespikeOptions& options, const float* frame, int channels, int samples,
                                     DespikeScratch* scratch, std::vector<float>* clipped, DespikeStats* stats) {
  LOCALIZER_RETURN_IF_ERROR(CheckArguments(options, frame, channels, samples));
  if (clipped == nullptr) return InvalidArgument("clipped (the copy's buffer) is null");
  if (stats != nullptr) stats->clipped_samples = 0;
  if (options.despike_k == 0.0) return frame;
  DespikeScratch local;
  DespikeScratch& buffers = scratch != nullptr ? *scratch : local;
  if (!ClipLimits(options, frame, channels, samples, buffers)) return frame;
  clipped->assign(frame, frame + static_cast<std::size_t>(channels) * samples);
  const int count = ClipOutliers(options, clipped->data(), channels, samples, buffers);
  if (stats != nullptr) stats->clipped_samples = count;
  return static_cast<const float*>(clipped->data());
}

}  // namespace localizer::engine
