#include "engine/filters/particle_set.h"

#include <algorithm>
#include <cmath>

#include <Eigen/Eigenvalues>

#include "engine/core/fast_math.h"

namespace localizer::engine {

void ParticleSet::Columns::Resize(int n) {
  for (auto* c : {&x, &y, &z, &vx, &vy, &vz}) c->assign(n, 0.0f);
}

ParticleSet::ParticleSet(const ArrayGeometry& array, const ParticleFilterOptions& options)
    : n_(options.particles),
      seed_(options.seed),
      origin_m_(array.centroid_m()),
      reference_(array.reference_sensor()),
      inv_c_(static_cast<float>(1.0 / array.sound_speed_mps())) {
  for (const Vec3& m : array.sensors_m()) {
    sensor_x_.push_back(static_cast<float>(m.x() - origin_m_.x()));
    sensor_y_.push_back(static_cast<float>(m.y() - origin_m_.y()));
    sensor_z_.push_back(static_cast<float>(m.z() - origin_m_.z()));
  }
  for (int p = 0; p < array.pair_count(); ++p) pair_sensor_.push_back(array.sensor_of_pair(p));
  cur_.Resize(n_);
  next_.Resize(n_);
  for (auto* v : {&logw_, &w_, &r_ref_, &vr_ref_, &loglik_}) v->assign(n_, 0.0f);
  for (auto& column : noise_) column.assign(n_, 0.0f);
  SetEqualWeights();
}

uint32_t ParticleSet::NextKey() {
  ++draws_;
  const uint32_t lo = static_cast<uint32_t>(seed_), hi = static_cast<uint32_t>(seed_ >> 32);
  return HashMix32(lo ^ HashMix32(hi + 0x9e3779b9U * static_cast<uint32_t>(draws_)));
}

void ParticleSet::SetEqualWeights() {
  const float logw = -std::log(static_cast<float>(n_));
  std::fill(logw_.begin(), logw_.end(), logw);
  std::fill(w_.begin(), w_.end(), 1.0f / static_cast<float>(n_));
}

void ParticleSet::SampleGaussian(const Vec6& mean, const Mat6& root) {
  Vec6 centre = mean;
  centre.head<3>() -= origin_m_;
  const Eigen::Matrix<float, 6, 6> l = root.cast<float>();
  const Eigen::Matrix<float, 6, 1> mu = centre.cast<float>();
  const uint32_t key = NextKey();
  float* cols[6] = {cur_.x.data(), cur_.y.data(), cur_.z.data(), cur_.vx.data(), cur_.vy.data(), cur_.vz.data()};
  for (int i = 0; i < n_; ++i) {
    float z[6];
    for (int k = 0; k < 6; ++k) z[k] = NormalFromUniform(UniformFromCounter(key, 6u * i + k));
    for (int r = 0; r < 6; ++r) {
      float v = mu(r);
      for (int k = 0; k < 6; ++k) v += l(r, k) * z[k];
      cols[r][i] = v;
    }
  }
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
  SetEqualWeights();
}

void ParticleSet::Predict(double dt_s, double accel_sigma_mps2) {
  const float dt = static_cast<float>(dt_s);
  const float a_to_v = static_cast<float>(accel_sigma_mps2 * dt_s);
  const float a_to_p = static_cast<float>(0.5 * accel_sigma_mps2 * dt_s * dt_s);
  const uint32_t key = NextKey();
  float* __restrict x = cur_.x.data();
  float* __restrict y = cur_.y.data();
  float* __restrict z = cur_.z.data();
  float* __restrict vx = cur_.vx.data();
  float* __restrict vy = cur_.vy.data();
  float* __restrict vz = cur_.vz.data();
#pragma omp simd
  for (int i = 0; i < n_; ++i) {
    const uint32_t c = 3u * static_cast<uint32_t>(i);
    const float ax = NormalFromUniform(UniformFromCounter(key, c));
    const float ay = NormalFromUniform(UniformFromCounter(key, c + 1));
    const float az = NormalFromUniform(UniformFromCounter(key, c + 2));
    x[i] += vx[i] * dt + a_to_p * ax;
    y[i] += vy[i] * dt + a_to_p * ay;
    z[i] += vz[i] * dt + a_to_p * az;
    vx[i] += a_to_v * ax;
    vy[i] += a_to_v * ay;
    vz[i] += a_to_v * az;
  }
}

double ParticleSet::Weigh(const Measurement& m, Likelihood likelihood, double sigma_s, double peak_dof,
                          double gcc_sharpness) {
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
      const float dx = x[i] - sx, dy = y[i] - sy, dz = z[i] - sz;
      const float r = std::sqrt(dx * dx + dy * dy + dz * dz) + 1e-6f;
      r_ref[i] = r;
      vr_ref[i] = (dx * vx[i] + dy * vy[i] + dz * vz[i]) / r;
      ll[i] = 0.0f;
    }
  }
  const float inv_sigma = static_cast<float>(1.0 / sigma_s);
  const float inv_dof = static_cast<float>(1.0 / peak_dof);
  const float half_dof_plus_1 = static_cast<float>(0.5 * (peak_dof + 1.0));
  const float inv_c = inv_c_;
  double nis = 0.0;
  for (size_t p = 0; p < m.pairs.size(); ++p) {
    const PairMeasurement& pm = m.pairs[p];
    const int k = pair_sensor_[p];
    const float sx = sensor_x_[k], sy = sensor_y_[k], sz = sensor_z_[k];
    const float d = static_cast<float>(pm.delay_s);
    const float half_d = 0.5f * d;
    // Prior moments of the innovation in sigmas, for the NIS.
    float sum_e = 0.0f, sum_e2 = 0.0f;
    const bool use_gcc = likelihood == Likelihood::kGcc && pm.gcc.size() >= 2;
    const float* __restrict gcc = use_gcc ? pm.gcc.data() : nullptr;
    const float last = use_gcc ? static_cast<float>(pm.gcc.size() - 1) - 1e-3f : 0.0f;
    const float lag_scale = static_cast<float>(m.sample_rate_hz);
    const float lag0 = static_cast<float>(pm.first_lag_samples);
    float gmax = 1e-12f;
    if (use_gcc) {
      for (float g : pm.gcc) gmax = std::max(gmax, g);
    }
    const float gcc_gain = static_cast<float>(gcc_sharpness) / gmax;
#pragma omp simd reduction(+ : sum_e, sum_e2)
    for (int i = 0; i < n_; ++i) {
      const float dx = x[i] - sx, dy = y[i] - sy, dz = z[i] - sz;
      const float r = std::sqrt(dx * dx + dy * dy + dz * dz) + 1e-6f;
      const float vr = (dx * vx[i] + dy * vy[i] + dz * vz[i]) / r;
      // Delay at the instant the pair describes: d/2 before the frame centre (first order).
      const float h = (r - r_ref[i]) * inv_c - half_d * (vr - vr_ref[i]) * inv_c;
      const float e = (d - h) * inv_sigma;
      sum_e += w[i] * e;
      sum_e2 += w[i] * e * e;
      if (gcc) {
        float lag = h * lag_scale - lag0;
        lag = lag < 0.0f ? 0.0f : (lag > last ? last : lag);
        const int i0 = static_cast<int>(lag);
        const float f = lag - static_cast<float>(i0);
        ll[i] += gcc_gain * (gcc[i0] + f * (gcc[i0 + 1] - gcc[i0]));
      } else {
        ll[i] -= half_dof_plus_1 * FastLog(1.0f + e * e * inv_dof);
      }
    }
    const double var = std::max(0.0, static_cast<double>(sum_e2) - static_cast<double>(sum_e) * sum_e);
    nis += static_cast<double>(sum_e) * sum_e / (1.0 + var);
  }
  float* __restrict logw = logw_.data();
#pragma omp simd
  for (int i = 0; i < n_; ++i) logw[i] += ll[i];
  return nis;
}

double ParticleSet::NormaliseWeights() {
  float* __restrict logw = logw_.data();
  float* __restrict w = w_.data();
  float max_logw = -INFINITY;
#pragma omp simd reduction(max : max_logw)
  for (int i = 0; i < n_; ++i) max_logw = std::max(max_logw, logw[i]);
  float sum = 0.0f;
#pragma omp simd reduction(+ : sum)
  for (int i = 0; i < n_; ++i) {
    w[i] = FastExp(logw[i] - max_logw);
    sum += w[i];
  }
  const float inv_sum = 1.0f / sum;
  const float log_sum = std::log(sum);
  float sum_w2 = 0.0f;
#pragma omp simd reduction(+ : sum_w2)
  for (int i = 0; i < n_; ++i) {
    w[i] *= inv_sum;
    logw[i] -= max_logw + log_sum;
    sum_w2 += w[i] * w[i];
  }
  return 1.0 / static_cast<double>(sum_w2);
}

void ParticleSet::ResampleSystematic(double kernel_scale) {
  const TrackState before = kernel_scale > 0.0 ? MeanAndCovariance() : TrackState{};
  const float u0 = UniformFromCounter(NextKey(), 0);
  const double step = 1.0 / n_;
  double cumulative = w_[0];
  int j = 0;
  for (int m = 0; m < n_; ++m) {
    const double u = (u0 + static_cast<double>(m)) * step;
    while (u > cumulative && j < n_ - 1) cumulative += w_[++j];
    next_.x[m] = cur_.x[j];
    next_.y[m] = cur_.y[j];
    next_.z[m] = cur_.z[j];
    next_.vx[m] = cur_.vx[j];
    next_.vy[m] = cur_.vy[j];
    next_.vz[m] = cur_.vz[j];
  }
  std::swap(cur_, next_);
  SetEqualWeights();
  if (kernel_scale > 0.0) Regularise(before, kernel_scale);
}

void ParticleSet::Regularise(const TrackState& moments, double kernel_scale) {
  const double d = 6.0;
  const double h = std::min(0.95, kernel_scale * std::pow(4.0 / (n_ * (d + 2.0)), 1.0 / (d + 4.0)));
  const double a = std::sqrt(1.0 - h * h);
  const Eigen::SelfAdjointEigenSolver<Mat6> eig(moments.covariance);
  const Mat6 root = eig.eigenvectors() * eig.eigenvalues().cwiseMax(0.0).cwiseSqrt().asDiagonal();
  const Eigen::Matrix<float, 6, 6> l = (h * root).cast<float>();
  Vec6 centre = moments.mean;
  centre.head<3>() -= origin_m_;
  const Eigen::Matrix<float, 6, 1> shift = ((1.0 - a) * centre).cast<float>();
  const float fa = static_cast<float>(a);
  const uint32_t key = NextKey();
  // Standard normals, one column per state dimension, then one FMA pass per state row.
  for (int k = 0; k < 6; ++k) {
    float* __restrict zk = noise_[k].data();
    const uint32_t offset = static_cast<uint32_t>(k) * static_cast<uint32_t>(n_);
#pragma omp simd
    for (int i = 0; i < n_; ++i) zk[i] = NormalFromUniform(UniformFromCounter(key, offset + static_cast<uint32_t>(i)));
  }
  float* cols[6] = {cur_.x.data(), cur_.y.data(), cur_.z.data(), cur_.vx.data(), cur_.vy.data(), cur_.vz.data()};
  const float* __restrict z0 = noise_[0].data();
  const float* __restrict z1 = noise_[1].data();
  const float* __restrict z2 = noise_[2].data();
  const float* __restrict z3 = noise_[3].data();
  const float* __restrict z4 = noise_[4].data();
  const float* __restrict z5 = noise_[5].data();
  for (int r = 0; r < 6; ++r) {
    float* __restrict col = cols[r];
    const float lr0 = l(r, 0), lr1 = l(r, 1), lr2 = l(r, 2), lr3 = l(r, 3), lr4 = l(r, 4), lr5 = l(r, 5);
    const float sr = shift(r);
#pragma omp simd
    for (int i = 0; i < n_; ++i) {
      col[i] = fa * col[i] + sr + lr0 * z0[i] + lr1 * z1[i] + lr2 * z2[i] + lr3 * z3[i] + lr4 * z4[i] + lr5 * z5[i];
    }
  }
}

TrackState ParticleSet::MeanAndCovariance() const {
  const float* cols[6] = {cur_.x.data(), cur_.y.data(), cur_.z.data(), cur_.vx.data(), cur_.vy.data(), cur_.vz.data()};
  const float* __restrict w = w_.data();
  float mean[6];
  for (int k = 0; k < 6; ++k) {
    const float* __restrict c = cols[k];
    float s = 0.0f;
#pragma omp simd reduction(+ : s)
    for (int i = 0; i < n_; ++i) s += w[i] * c[i];
    mean[k] = s;
  }
  TrackState state;
  for (int a = 0; a < 6; ++a) {
    for (int b = a; b < 6; ++b) {
      const float* __restrict ca = cols[a];
      const float* __restrict cb = cols[b];
      const float ma = mean[a], mb = mean[b];
      float s = 0.0f;
#pragma omp simd reduction(+ : s)
      for (int i = 0; i < n_; ++i) s += w[i] * (ca[i] - ma) * (cb[i] - mb);
      state.covariance(a, b) = state.covariance(b, a) = s;
    }
    state.mean(a) = mean[a];
  }
  state.mean.head<3>() += origin_m_;
  return state;
}

}  // namespace localizer::engine
