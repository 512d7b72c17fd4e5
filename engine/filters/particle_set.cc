#include "engine/filters/particle_set.h"

#include <algorithm>
#include <cmath>
#include <utility>

#include "engine/core/fast_math.h"
#include "engine/filters/gcc_upsampling.h"
#include "engine/filters/lane_sums.h"

namespace localizer::engine {

void ParticleSet::Columns::Resize(int n) {
  for (auto* c : {&x, &y, &z, &vx, &vy, &vz}) c->assign(n, 0.0f);
}

void ParticleSet::SetSensors(const ArrayGeometry& array) {
  sensor_x_.clear();
  sensor_y_.clear();
  sensor_z_.clear();
  for (const Vec3& m : array.sensors_m()) {
    sensor_x_.push_back(static_cast<float>(m.x() - origin_m_.x()));
    sensor_y_.push_back(static_cast<float>(m.y() - origin_m_.y()));
    sensor_z_.push_back(static_cast<float>(m.z() - origin_m_.z()));
  }
}

ParticleSet::ParticleSet(const ArrayGeometry& array, const ParticleFilterOptions& options)
    : n_(options.particles),
      seed_(options.seed),
      origin_m_(array.centroid_m()),
      reference_(array.reference_sensor()),
      outlier_probability_(static_cast<float>(options.outlier_probability)),
      motion_blur_(static_cast<float>(options.motion_blur)),
      inv_c_(static_cast<float>(1.0 / array.sound_speed_mps())) {
  SetSensors(array);
  for (int p = 0; p < array.pair_count(); ++p) {
    pair_sensor_.push_back(array.sensor_of_pair(p));
    pair_span_s_.push_back(static_cast<float>(2.0 * array.max_delay_s(p)));
  }
  cur_.Resize(n_);
  next_.Resize(n_);
  for (auto* v : {&logw_, &w_, &r_ref_, &vr_ref_, &loglik_, &delay_}) v->assign(n_, 0.0f);
  if (motion_blur_ > 0.0f) widen_.assign(n_, 1.0f);
  for (auto& column : noise_) column.assign(n_, 0.0f);
  index_.assign(n_, 0);
  accel_.assign(2 * ((3 * static_cast<size_t>(n_) + 1) / 2), 0.0f);
  first_slot_.assign(n_, 0);
  SetEqualWeights();
}

uint32_t ParticleSet::NextKey() {
  ++draws_;
  const uint32_t lo = static_cast<uint32_t>(seed_), hi = static_cast<uint32_t>(seed_ >> 32);
  return HashMix32(lo ^ HashMix32(hi + 0x9e3779b9U * static_cast<uint32_t>(draws_)));
}

void ParticleSet::SetEqualWeights() {
  moments_valid_ = false;
  const float logw = -std::log(static_cast<float>(n_));
  std::fill(logw_.begin(), logw_.end(), logw);
  std::fill(w_.begin(), w_.end(), 1.0f / static_cast<float>(n_));
}

void ParticleSet::SampleGaussianRange(const Vec6& mean, const Mat6& root, uint32_t key, int first, int end) {
  Vec6 centre = mean;
  centre.head<3>() -= origin_m_;
  const Eigen::Matrix<float, 6, 6> l = root.cast<float>();
  const Eigen::Matrix<float, 6, 1> mu = centre.cast<float>();
  const std::array<float*, 6> cols = cur_.Pointers();
  for (int i = first; i < end; ++i) {
    float z[6];
    for (int k = 0; k < 6; ++k) z[k] = NormalFromUniform(UniformFromCounter(key, 6u * i + k));
    for (int r = 0; r < 6; ++r) {
      float v = mu(r);
      for (int k = 0; k < 6; ++k) v += l(r, k) * z[k];
      cols[r][i] = v;
    }
  }
}

void ParticleSet::SampleGaussian(const Vec6& mean, const Mat6& root) {
  SampleGaussianRange(mean, root, NextKey(), 0, n_);
  DrawLevels();
  labels_ = 1;
  if (bounded_) ApplyBounds();
  SetEqualWeights();
}

void ParticleSet::SampleUniformBox(const Vec3& min_m, const Vec3& max_m, double speed_sigma_mps) {
  const Vec3 lo = min_m - origin_m_, span = max_m - min_m;
  const uint32_t key = NextKey();
  const float s = static_cast<float>(speed_sigma_mps);
  for (int i = 0; i < n_; ++i) {
    const uint32_t c = 6u * i;
    cur_.x[i] = static_cast<float>(lo.x() + span.x() * UniformFromCounter(key, c));
    cur_.y[i] = static_cast<float>(lo.y() + span.y() * UniformFromCounter(key, c + 1));
    cur_.z[i] = static_cast<float>(lo.z() + span.z() * UniformFromCounter(key, c + 2));
    cur_.vx[i] = s * NormalFromUniform(UniformFromCounter(key, c + 3));
    cur_.vy[i] = s * NormalFromUniform(UniformFromCounter(key, c + 4));
    cur_.vz[i] = s * NormalFromUniform(UniformFromCounter(key, c + 5));
  }
  labels_ = 1;
  DrawLevels();
  if (bounded_) ApplyBounds();
  SetEqualWeights();
}

void ParticleSet::CopyCloudFrom(const ParticleSet& other) {
  cur_.x = other.cur_.x;
  cur_.y = other.cur_.y;
  cur_.z = other.cur_.z;
  cur_.vx = other.cur_.vx;
  cur_.vy = other.cur_.vy;
  cur_.vz = other.cur_.vz;
  logw_ = other.logw_;
  w_ = other.w_;
  moments_ = other.moments_;
  moments_valid_ = other.moments_valid_;
  label_ = other.label_;
  labels_ = other.labels_;
  label_deficit_ = other.label_deficit_;
  gain_ = other.gain_;
  turn_ = other.turn_;
  speed_change_ = other.speed_change_;
}

double ParticleSet::TakeParticles(const std::vector<const ParticleSet*>& candidates, const std::vector<uint8_t>& choice,
                                  std::span<const float> log_weights) {
  moments_valid_ = false;
  for (int i = 0; i < n_; ++i) {
    const Columns& from = candidates[choice[i]]->cur_;
    cur_.x[i] = from.x[i];
    cur_.y[i] = from.y[i];
    cur_.z[i] = from.z[i];
    cur_.vx[i] = from.vx[i];
    cur_.vy[i] = from.vy[i];
    cur_.vz[i] = from.vz[i];
  }
  if (log_weights.data() != logw_.data()) logw_.assign(log_weights.begin(), log_weights.end());  // may be its own
  labels_ = 1;  // the multiple-model filter starts single-mode and keeps no labels
  return NormaliseWeights();
}

double GccGain(const std::vector<float>& gcc, double sigma_samples, double sharpness) {
  size_t peak = 1;
  for (size_t k = 1; k + 1 < gcc.size(); ++k) {
    if (gcc[k] > gcc[peak]) peak = k;
  }
  const double curvature = std::max(1e-6, 2.0 * gcc[peak] - gcc[peak - 1] - gcc[peak + 1]);
  return sharpness / (sigma_samples * sigma_samples * curvature);
}

void ParticleSet::Weigh(const Measurement& m, const std::vector<int>& used, Likelihood likelihood,
                        const std::vector<double>& sigmas_s, double peak_dof, double gcc_sharpness,
                        std::vector<InnovationMoments>* innovations, float exponent) {
  innovations->resize(m.pairs.size());
  const float* __restrict x = cur_.x.data();
  const float* __restrict y = cur_.y.data();
  const float* __restrict z = cur_.z.data();
  const float* __restrict vx = cur_.vx.data();
  const float* __restrict vy = cur_.vy.data();
  const float* __restrict vz = cur_.vz.data();
  const float* __restrict w = w_.data();
  float* __restrict r_ref = r_ref_.data();
  float* __restrict vr_ref = vr_ref_.data();
  float* __restrict ll = loglik_.data();
  {
    const float sx = sensor_x_[reference_], sy = sensor_y_[reference_], sz = sensor_z_[reference_];
#pragma omp simd
    for (int i = 0; i < n_; ++i) {
      const RangeRate ref = RangeAndRate(x[i] - sx, y[i] - sy, z[i] - sz, vx[i], vy[i], vz[i]);
      r_ref[i] = ref.r;
      vr_ref[i] = ref.vr;
      ll[i] = 0.0f;
    }
  }
  const float inv_dof = static_cast<float>(1.0 / peak_dof);
  const float half_dof_plus_1 = static_cast<float>(0.5 * (peak_dof + 1.0));
  const float inv_c = inv_c_;
  for (size_t p = 0; p < m.pairs.size(); ++p) {
    if (!used[p]) continue;
    const PairMeasurement& pm = m.pairs[p];
    const double sigma_s = sigmas_s[p];
    const float inv_sigma = static_cast<float>(1.0 / sigma_s);
    const int k = pair_sensor_[p];
    const float sx = sensor_x_[k], sy = sensor_y_[k], sz = sensor_z_[k];
    const float d = static_cast<float>(pm.delay_s);
    const float half_d = 0.5f * d;
    // Prior moments of the innovation in sigmas, for the NIS.
    float sum_e = 0.0f, sum_e2 = 0.0f;
    const bool use_gcc = likelihood == Likelihood::kGcc && pm.gcc.size() >= 4;
    if (use_gcc) UpsampleGcc(pm.gcc, kGccUpsampling, &fine_gcc_);
    const float* __restrict gcc = use_gcc ? fine_gcc_.data() : nullptr;
    // Cubic (Catmull-Rom) reads need fine lags 1 .. size-3 around the interval.
    const float last = use_gcc ? static_cast<float>(fine_gcc_.size() - 3) - 1e-3f : 0.0f;
    const float lag_scale = static_cast<float>(m.sample_rate_hz * kGccUpsampling);
    const float lag0 = static_cast<float>(pm.first_lag_samples * kGccUpsampling);
    const float gcc_gain =
        use_gcc ? static_cast<float>(GccGain(fine_gcc_, sigma_s * m.sample_rate_hz * kGccUpsampling, gcc_sharpness))
                : 0.0f;
    float* __restrict hk = delay_.data();
    // The delay at the instant the pair describes: d/2 before the frame centre (first order).
    // With motion blur (ParticleFilterOptions::motion_blur) also each particle's pair variance
    // in sigma_p^2 units, 1 + K r^2 V / sigma_p^2 with r its delay rate.
    const double blur_var_s2 = use_gcc ? 0.0 : MotionBlurVariance(motion_blur_, m.window_time_var_s2, pm.peak_snr);
    const bool blurred = blur_var_s2 > 0.0;
    if (blurred) {
      const auto blur = static_cast<float>(blur_var_s2 / (sigma_s * sigma_s)) * inv_c * inv_c;
      float* __restrict wide = widen_.data();
#pragma omp simd
      for (int i = 0; i < n_; ++i) {
        const RangeRate sensor = RangeAndRate(x[i] - sx, y[i] - sy, z[i] - sz, vx[i], vy[i], vz[i]);
        hk[i] = PairDelay(sensor.r, sensor.vr, r_ref[i], vr_ref[i], half_d, inv_c);
        const float range_rate_mps = sensor.vr - vr_ref[i];
        wide[i] = 1.0f + blur * range_rate_mps * range_rate_mps;
      }
    } else {
#pragma omp simd
      for (int i = 0; i < n_; ++i) {
        const RangeRate sensor = RangeAndRate(x[i] - sx, y[i] - sy, z[i] - sz, vx[i], vy[i], vz[i]);
        hk[i] = PairDelay(sensor.r, sensor.vr, r_ref[i], vr_ref[i], half_d, inv_c);
      }
    }
    {
      float sums[2];
      LaneSums<float, 2>(
          0, n_, {0.0f, 0.0f},
          [&](int i, int lane, float(*acc)[kSumLanes<float>]) {
            const float e = (d - hk[i]) * inv_sigma;
            const float we = w[i] * e;
            acc[0][lane] += we;
            acc[1][lane] = FusedMulAdd(we, e, acc[1][lane]);
          },
          sums);
      sum_e = sums[0];
      sum_e2 = sums[1];
    }
    if (gcc) {
#pragma omp simd
      for (int i = 0; i < n_; ++i) ll[i] += gcc_gain * CatmullRomRead(gcc, GccFineLag(hk[i], lag_scale, lag0), last);
    } else if (likelihood == Likelihood::kMixture) {
      // log(exp(-e^2 / 2) + floor) is the mixture's log-density up to a constant, with
      // floor = (eps / W) / ((1 - eps) / (sigma sqrt(2 pi))).
      const double eps = outlier_probability_;
      const auto floor = static_cast<float>(eps / pair_span_s_[p] * sigma_s * 2.5066282746310002 / (1.0 - eps));
      if (blurred) {
        const float* __restrict wide = widen_.data();
#pragma omp simd
        for (int i = 0; i < n_; ++i) {
          const float e = (d - hk[i]) * inv_sigma;
          ll[i] += FastLog(FastExp(-0.5f * (e * e / wide[i] + FastLog(wide[i]))) + floor);
        }
      } else {
#pragma omp simd
        for (int i = 0; i < n_; ++i) {
          const float e = (d - hk[i]) * inv_sigma;
          ll[i] += FastLog(FastExp(-0.5f * e * e) + floor);
        }
      }
    } else if (blurred) {
      const float* __restrict wide = widen_.data();
#pragma omp simd
      for (int i = 0; i < n_; ++i) {
        const float e = (d - hk[i]) * inv_sigma;
        ll[i] -= half_dof_plus_1 * FastLog(1.0f + e * e * inv_dof / wide[i]) + 0.5f * FastLog(wide[i]);
      }
    } else {
#pragma omp simd
      for (int i = 0; i < n_; ++i) {
        const float e = (d - hk[i]) * inv_sigma;
        ll[i] -= half_dof_plus_1 * FastLog(1.0f + e * e * inv_dof);
      }
    }
    const double var = std::max(0.0, static_cast<double>(sum_e2) - static_cast<double>(sum_e) * sum_e);
    (*innovations)[p].mean_s = static_cast<double>(sum_e) * sigma_s;
    (*innovations)[p].predicted_var_s2 = var * sigma_s * sigma_s;
  }
  float* __restrict logw = logw_.data();
#pragma omp simd
  for (int i = 0; i < n_; ++i) logw[i] += exponent * ll[i];
  if (labels_ > 1) ScoreLabels(exponent);
}

double ParticleSet::NormaliseWeights() {
  moments_valid_ = false;
  float* __restrict logw = logw_.data();
  float* __restrict w = w_.data();
  // The largest log-weight, from kLanes running maxima (GCC 12 leaves this file's
  // `omp simd reduction(max)` scalar: one 4-cycle vmaxss chain per particle).
  constexpr int kLanes = 16;
  float lane_max[kLanes];
  for (float& m : lane_max) m = -INFINITY;
  const int n = n_;
  int block = 0;
  for (; block + kLanes <= n; block += kLanes) {
#pragma omp simd
    for (int k = 0; k < kLanes; ++k) lane_max[k] = logw[block + k] > lane_max[k] ? logw[block + k] : lane_max[k];
  }
  float max_logw = -INFINITY;
  for (const float m : lane_max) max_logw = std::max(max_logw, m);
  for (; block < n; ++block) max_logw = std::max(max_logw, logw[block]);
#pragma omp simd
  for (int i = 0; i < n; ++i) w[i] = FastExp(logw[i] - max_logw);
  float sum[1];
  LaneSums<float, 1>(
      0, n, {0.0f}, [&](int i, int lane, float(*acc)[kSumLanes<float>]) { acc[0][lane] += w[i]; }, sum);
  const float inv_sum = 1.0f / sum[0];
  const float log_sum = std::log(sum[0]);
#pragma omp simd
  for (int i = 0; i < n; ++i) {
    w[i] *= inv_sum;
    logw[i] -= max_logw + log_sum;
  }
  float sum_w2[1];
  LaneSums<float, 1>(
      0, n, {0.0f},
      [&](int i, int lane, float(*acc)[kSumLanes<float>]) { acc[0][lane] = FusedMulAdd(w[i], w[i], acc[0][lane]); },
      sum_w2);
  return 1.0 / static_cast<double>(sum_w2[0]);
}

double ParticleSet::EssIfUntempered(float r) const {
  const float* __restrict logw = logw_.data();
  const float* __restrict ll = loglik_.data();
  float max_lw = -INFINITY;
  for (int i = 0; i < n_; ++i) max_lw = std::max(max_lw, logw[i] - r * ll[i]);
  float sums[2];
  LaneSums<float, 2>(
      0, n_, {0.0f, 0.0f},
      [&](int i, int lane, float(*acc)[kSumLanes<float>]) {
        const float w = FastExp(logw[i] - r * ll[i] - max_lw);
        acc[0][lane] += w;
        acc[1][lane] = FusedMulAdd(w, w, acc[1][lane]);
      },
      sums);
  return static_cast<double>(sums[0]) * sums[0] / static_cast<double>(sums[1]);
}

double ParticleSet::Untemper(float r) {
  float* __restrict logw = logw_.data();
  const float* __restrict ll = loglik_.data();
#pragma omp simd
  for (int i = 0; i < n_; ++i) logw[i] -= r * ll[i];
  return NormaliseWeights();
}

TrackState ParticleSet::MeanAndCovariance() const {
  if (moments_valid_) return moments_;
  // One pass, accumulating about a shift point near the cloud (particle 0) so float sums
  // of squares do not cancel: cov = E[(x - s)(y - s)] - (m - s)(m - s)^T.
  const float* __restrict x = cur_.x.data();
  const float* __restrict y = cur_.y.data();
  const float* __restrict z = cur_.z.data();
  const float* __restrict vx = cur_.vx.data();
  const float* __restrict vy = cur_.vy.data();
  const float* __restrict vz = cur_.vz.data();
  const float* __restrict w = w_.data();
  const float s0 = x[0], s1 = y[0], s2 = z[0], s3 = vx[0], s4 = vy[0], s5 = vz[0];
  // The 27 sums: 6 means, then the upper triangle of the second moments row by row.
  float sums[27];
  float zeros[27] = {};
  LaneSums<float, 27>(
      0, n_, zeros,
      [&](int i, int lane, float(*acc)[kSumLanes<float>]) {
        const float wi = w[i];
        const float d0 = x[i] - s0, d1 = y[i] - s1, d2 = z[i] - s2, d3 = vx[i] - s3, d4 = vy[i] - s4, d5 = vz[i] - s5;
        const float w0 = wi * d0, w1 = wi * d1, w2 = wi * d2, w3 = wi * d3, w4 = wi * d4;
        const float w5 = wi * d5;
        acc[0][lane] += w0, acc[1][lane] += w1, acc[2][lane] += w2, acc[3][lane] += w3, acc[4][lane] += w4;
        acc[5][lane] += w5;
        // The second moments fused, as the reduction loop had them (lane_sums.h).
        acc[6][lane] = FusedMulAdd(w0, d0, acc[6][lane]);
        acc[7][lane] = FusedMulAdd(w0, d1, acc[7][lane]);
        acc[8][lane] = FusedMulAdd(w0, d2, acc[8][lane]);
        acc[9][lane] = FusedMulAdd(w0, d3, acc[9][lane]);
        acc[10][lane] = FusedMulAdd(w0, d4, acc[10][lane]);
        acc[11][lane] = FusedMulAdd(w0, d5, acc[11][lane]);
        acc[12][lane] = FusedMulAdd(w1, d1, acc[12][lane]);
        acc[13][lane] = FusedMulAdd(w1, d2, acc[13][lane]);
        acc[14][lane] = FusedMulAdd(w1, d3, acc[14][lane]);
        acc[15][lane] = FusedMulAdd(w1, d4, acc[15][lane]);
        acc[16][lane] = FusedMulAdd(w1, d5, acc[16][lane]);
        acc[17][lane] = FusedMulAdd(w2, d2, acc[17][lane]);
        acc[18][lane] = FusedMulAdd(w2, d3, acc[18][lane]);
        acc[19][lane] = FusedMulAdd(w2, d4, acc[19][lane]);
        acc[20][lane] = FusedMulAdd(w2, d5, acc[20][lane]);
        acc[21][lane] = FusedMulAdd(w3, d3, acc[21][lane]);
        acc[22][lane] = FusedMulAdd(w3, d4, acc[22][lane]);
        acc[23][lane] = FusedMulAdd(w3, d5, acc[23][lane]);
        acc[24][lane] = FusedMulAdd(w4, d4, acc[24][lane]);
        acc[25][lane] = FusedMulAdd(w4, d5, acc[25][lane]);
        acc[26][lane] = FusedMulAdd(w5, d5, acc[26][lane]);
      },
      sums);
  const float m0 = sums[0], m1 = sums[1], m2 = sums[2], m3 = sums[3], m4 = sums[4], m5 = sums[5];
  const float c00 = sums[6], c01 = sums[7], c02 = sums[8], c03 = sums[9], c04 = sums[10], c05 = sums[11];
  const float c11 = sums[12], c12 = sums[13], c13 = sums[14], c14 = sums[15], c15 = sums[16];
  const float c22 = sums[17], c23 = sums[18], c24 = sums[19], c25 = sums[20];
  const float c33 = sums[21], c34 = sums[22], c35 = sums[23], c44 = sums[24], c45 = sums[25], c55 = sums[26];
  const Vec6 m(m0, m1, m2, m3, m4, m5);
  Mat6 c;
  c << c00, c01, c02, c03, c04, c05, c01, c11, c12, c13, c14, c15, c02, c12, c22, c23, c24, c25, c03, c13, c23, c33,
      c34, c35, c04, c14, c24, c34, c44, c45, c05, c15, c25, c35, c45, c55;
  TrackState state;
  state.covariance = c - m * m.transpose();
  state.mean = m + Vec6(s0, s1, s2, s3, s4, s5);
  state.mean.head<3>() += origin_m_;
  moments_ = state;
  moments_valid_ = true;
  return state;
}

}  // namespace localizer::engine
