// ParticleSet's motion: the prediction step (constant velocity, mean-reverting velocity and
// the coordinated turn), the white acceleration's normals, and the per-particle acceleration
// levels and manoeuvre gains that scale them (particle_set.h). Built with the same 512-bit
// vector option as particle_set.cc (engine/CMakeLists.txt): the draws are compute-bound.
#include <algorithm>
#include <cmath>

#include "engine/core/fast_math.h"
#include "engine/filters/particle_set.h"

namespace localizer::engine {

void ParticleSet::Predict(double dt_s, double accel_sigma_mps2, double velocity_time_constant_s) {
  const double tau = velocity_time_constant_s;
  const double decay = tau > 0.0 ? std::exp(-dt_s / tau) : 1.0;
  const float dt = static_cast<float>(tau > 0.0 ? tau * (1.0 - decay) : dt_s);  // the velocity's reach
  const float d = static_cast<float>(decay);
  const float a_to_v = static_cast<float>(accel_sigma_mps2 * dt_s);
  const float a_to_p = static_cast<float>(0.5 * accel_sigma_mps2 * dt_s * dt_s);
  const uint32_t key = NextKey();
  moments_valid_ = false;
  const int n = n_;
  if (d == 1.0f && gain_.empty() && turn_.empty() && manoeuvre_share_ <= 0.0f && n % 2 == 0) {
    PredictConstantVelocity(key, dt, a_to_p, a_to_v);
    if (bounded_) ApplyBounds();
    return;
  }
  DrawAccelNormals(key, dt_s);  // axis k of particle i reads accel_[k * N + i]
  const float* __restrict ax = accel_.data();
  const float* __restrict ay = accel_.data() + n;
  const float* __restrict az = accel_.data() + 2 * n;
  float* __restrict x = cur_.x.data();
  float* __restrict y = cur_.y.data();
  float* __restrict z = cur_.z.data();
  float* __restrict vx = cur_.vx.data();
  float* __restrict vy = cur_.vy.data();
  float* __restrict vz = cur_.vz.data();
  if (!turn_.empty()) {  // ParticleFilterOptions::Validate: only with constant velocity
    PredictPersistentTurns(dt, a_to_p, a_to_v);
  } else if (d == 1.0f) {  // constant velocity: the GPU filter's step (particle_math.h)
#pragma omp simd
    for (int i = 0; i < n; ++i) {
      PredictAxis(x[i], vx[i], dt, a_to_p, a_to_v, ax[i]);
      PredictAxis(y[i], vy[i], dt, a_to_p, a_to_v, ay[i]);
      PredictAxis(z[i], vz[i], dt, a_to_p, a_to_v, az[i]);
    }
  } else {
#pragma omp simd
    for (int i = 0; i < n; ++i) {
      PredictAxisReverting(x[i], vx[i], dt, d, a_to_p, a_to_v, ax[i]);
      PredictAxisReverting(y[i], vy[i], dt, d, a_to_p, a_to_v, ay[i]);
      PredictAxisReverting(z[i], vz[i], dt, d, a_to_p, a_to_v, az[i]);
    }
  }
  if (bounded_) ApplyBounds();
}

void ParticleSet::PredictConstantVelocity(uint32_t key, float dt, float a_to_p, float a_to_v) {
  // DrawAccelNormals' draws without storing them: Box-Muller pair j gives accel_[j] and
  // accel_[3N/2 + j] (uniforms 2j and 2j + 1), and axis k of particle i reads accel_[k N + i].
  // So particles i and i + N/2 take their six normals from pairs i, N + i and N/2 + i:
  //   pair i:       x of i,  y of i + N/2;
  //   pair N + i:   y of i,  z of i + N/2;
  //   pair N/2 + i: x of i + N/2,  z of i.
  // The same values as the stored path, without its 3N stores and loads (N even).
  const int half = n_ / 2;
  const uint32_t un = static_cast<uint32_t>(n_), uhalf = static_cast<uint32_t>(half);
  float* __restrict x = cur_.x.data();
  float* __restrict y = cur_.y.data();
  float* __restrict z = cur_.z.data();
  float* __restrict vx = cur_.vx.data();
  float* __restrict vy = cur_.vy.data();
  float* __restrict vz = cur_.vz.data();
  const auto pair = [key](uint32_t j, float* first, float* second) {
    NormalPairFromUniforms(UniformFromCounter(key, 2u * j), UniformFromCounter(key, 2u * j + 1), first, second);
  };
#pragma omp simd
  for (int i = 0; i < half; ++i) {
    const uint32_t u = static_cast<uint32_t>(i);
    float ax, ay, az, bx, by, bz;  // particle i's and particle i + N/2's normals
    pair(u, &ax, &by);
    pair(un + u, &ay, &bz);
    pair(uhalf + u, &bx, &az);
    const int k = i + half;
    PredictAxis(x[i], vx[i], dt, a_to_p, a_to_v, ax);
    PredictAxis(y[i], vy[i], dt, a_to_p, a_to_v, ay);
    PredictAxis(z[i], vz[i], dt, a_to_p, a_to_v, az);
    PredictAxis(x[k], vx[k], dt, a_to_p, a_to_v, bx);
    PredictAxis(y[k], vy[k], dt, a_to_p, a_to_v, by);
    PredictAxis(z[k], vz[k], dt, a_to_p, a_to_v, bz);
  }
}

float ParticleSet::SwitchProbability(double rate_hz, double dt_s) {
  return static_cast<float>(-std::expm1(-rate_hz * std::max(0.0, dt_s)));
}

// A per-particle value and its resampling scratch: n entries when on, none when off.
static void PerParticle(bool on, int n, std::vector<float>* value, std::vector<float>* scratch) {
  value->assign(on ? n : 0, 1.0f);
  scratch->assign(on ? n : 0, 1.0f);
}

void ParticleSet::SetAccelLevels(double floor, double ceiling, double switch_rate_hz) {
  log_level_floor_ = static_cast<float>(std::log(floor));
  log_level_ceiling_ = static_cast<float>(std::log(ceiling));
  level_switch_rate_hz_ = switch_rate_hz;
  const bool on = !(floor == 1.0 && ceiling == 1.0);  // ParticleFilterOptions::accel_levels
  PerParticle(on, n_, &gain_, &next_gain_);
  if (on) DrawLevels();
}

void ParticleSet::SetTurnRates(double max_radps, double switch_rate_hz) {
  turn_max_radps_ = static_cast<float>(max_radps);
  turn_switch_rate_hz_ = switch_rate_hz;
  PerParticle(max_radps != 0.0, n_, &turn_, &next_turn_);
  if (max_radps != 0.0) DrawLevels();
}

void ParticleSet::DrawLevels() {
  if (!turn_.empty()) {  // off: no key drawn, so the random stream is as before
    const uint32_t key = NextKey();
    for (int i = 0; i < n_; ++i) {
      turn_[i] = turn_max_radps_ * (2.0f * UniformFromCounter(key, static_cast<uint32_t>(i)) - 1.0f);
    }
  }
  if (gain_.empty()) return;  // off: no key drawn, so the random stream is as before
  const uint32_t key = NextKey();
  const float lo = log_level_floor_, span = log_level_ceiling_ - log_level_floor_;
  for (int i = 0; i < n_; ++i) gain_[i] = std::exp(lo + span * UniformFromCounter(key, static_cast<uint32_t>(i)));
}

void ParticleSet::CarryLevels() {
  if (!turn_.empty()) {
    for (int m = 0; m < n_; ++m) next_turn_[m] = turn_[index_[m]];
    std::swap(turn_, next_turn_);
  }
  if (gain_.empty()) return;
  for (int m = 0; m < n_; ++m) next_gain_[m] = gain_[index_[m]];
  std::swap(gain_, next_gain_);
}

void ParticleSet::DrawAccelNormals(uint32_t key, double dt_s) {
  const float switch_probability = SwitchProbability(level_switch_rate_hz_, dt_s);
  // 3N standard normals, two per Box–Muller draw: accel_[j] and accel_[half + j] come from
  // uniforms 2j and 2j + 1.
  const int half = static_cast<int>(accel_.size() / 2);
  float* __restrict first = accel_.data();
  float* __restrict second = accel_.data() + half;
#pragma omp simd
  for (int j = 0; j < half; ++j) {
    const uint32_t c = 2u * static_cast<uint32_t>(j);
    NormalPairFromUniforms(UniformFromCounter(key, c), UniformFromCounter(key, c + 1), &first[j], &second[j]);
  }
  if (!gain_.empty()) {
    // Particle i's level jumps when its uniform (counters past the normals') is below the
    // switch probability; the new gain takes the next counter. Then its normals scale.
    const int n = n_;
    const uint32_t base = static_cast<uint32_t>(accel_.size());
    const float lo = log_level_floor_, span = log_level_ceiling_ - log_level_floor_;
    float* __restrict a = accel_.data();
    float* __restrict g = gain_.data();
    for (int i = 0; i < n; ++i) {
      const uint32_t c = base + 2u * static_cast<uint32_t>(i);
      if (UniformFromCounter(key, c) < switch_probability) g[i] = std::exp(lo + span * UniformFromCounter(key, c + 1));
      a[i] *= g[i];
      a[n + i] *= g[i];
      a[2 * n + i] *= g[i];
    }
  }
  if (!turn_.empty()) {
    // Particle i redraws its turn rate when its uniform (counters past the levels' and the
    // manoeuvres') is below the switch probability; the new rate takes the next counter.
    const float p = SwitchProbability(turn_switch_rate_hz_, dt_s);
    const uint32_t base = static_cast<uint32_t>(accel_.size() + 2 * gain_.size() + n_);
    for (int i = 0; i < n_; ++i) {
      const uint32_t c = base + 2u * static_cast<uint32_t>(i);
      if (UniformFromCounter(key, c) < p) turn_[i] = turn_max_radps_ * (2.0f * UniformFromCounter(key, c + 1) - 1.0f);
    }
  }
  if (manoeuvre_share_ <= 0.0f) return;
  // Particle i manoeuvres this step when its uniform (counters past the normals') is below
  // the share: its three axes' normals take the manoeuvre gain, the others the quiet gain.
  const int n = n_;
  const uint32_t base = static_cast<uint32_t>(accel_.size() + 2 * gain_.size());
  const float share = manoeuvre_share_, quiet = quiet_gain_, loud = manoeuvre_gain_;
  float* __restrict a = accel_.data();
  for (int i = 0; i < n; ++i) {
    const float g = UniformFromCounter(key, base + static_cast<uint32_t>(i)) < share ? loud : quiet;
    a[i] *= g;
    a[n + i] *= g;
    a[2 * n + i] *= g;
  }
}

void ParticleSet::SetManoeuvre(double share, double scale) {
  const ManoeuvreGains gains = ManoeuvreGainsFor(share, scale);
  manoeuvre_share_ = static_cast<float>(share);
  quiet_gain_ = static_cast<float>(gains.quiet);
  manoeuvre_gain_ = static_cast<float>(gains.manoeuvre);
}

ManoeuvreGains ManoeuvreGainsFor(double share, double scale) {
  const double quiet = 1.0 / std::sqrt(1.0 - share + share * scale * scale);
  return {quiet, scale * quiet};
}

void ParticleSet::PredictPersistentTurns(float dt, float a_to_p, float a_to_v) {
  const int n = n_;
  const float* __restrict ax = accel_.data();
  const float* __restrict ay = accel_.data() + n;
  const float* __restrict az = accel_.data() + 2 * n;
  const float* __restrict w = turn_.data();
  float* __restrict x = cur_.x.data();
  float* __restrict y = cur_.y.data();
  float* __restrict z = cur_.z.data();
  float* __restrict vx = cur_.vx.data();
  float* __restrict vy = cur_.vy.data();
  float* __restrict vz = cur_.vz.data();
  if (turn_max_radps_ * dt <= 0.5f) {
    // sin(t)/t and (1 - cos t)/t to t^4 and t^5: float-exact for |t| <= 0.5 (the next terms
    // are below 3e-6 relative), and vectorised where sin and cos per particle would not be.
#pragma omp simd
    for (int i = 0; i < n; ++i) {
      const float t = w[i] * dt, t2 = t * t;
      const float sinc = 1.0f - t2 * (1.0f / 6.0f - t2 * (1.0f / 120.0f));
      const float cosc = t * (0.5f - t2 * (1.0f / 24.0f - t2 * (1.0f / 720.0f)));
      const float s = t * sinc, c = 1.0f - t * cosc;
      const float ux = vx[i], uy = vy[i];
      x[i] += dt * (sinc * ux - cosc * uy) + a_to_p * ax[i];
      y[i] += dt * (cosc * ux + sinc * uy) + a_to_p * ay[i];
      z[i] += dt * vz[i] + a_to_p * az[i];
      vx[i] = c * ux - s * uy + a_to_v * ax[i];
      vy[i] = s * ux + c * uy + a_to_v * ay[i];
      vz[i] += a_to_v * az[i];
    }
    return;
  }
  for (int i = 0; i < n; ++i) {  // a long step (a gap in the frames): exact, per particle
    const double t = static_cast<double>(w[i]) * dt;
    const double s = std::sin(t), c = std::cos(t);
    const double sinc = t == 0.0 ? 1.0 : s / t, cosc = t == 0.0 ? 0.0 : (1.0 - c) / t;
    const double ux = vx[i], uy = vy[i];
    x[i] += static_cast<float>(dt * (sinc * ux - cosc * uy)) + a_to_p * ax[i];
    y[i] += static_cast<float>(dt * (cosc * ux + sinc * uy)) + a_to_p * ay[i];
    z[i] += dt * vz[i] + a_to_p * az[i];
    vx[i] = static_cast<float>(c * ux - s * uy) + a_to_v * ax[i];
    vy[i] = static_cast<float>(s * ux + c * uy) + a_to_v * ay[i];
    vz[i] += a_to_v * az[i];
  }
}

void ParticleSet::PredictTurn(double dt_s, double turn_rate_radps, double accel_sigma_mps2, uint32_t key) {
  // The turn's coefficients in double, once.
  const double w = turn_rate_radps, wt = w * dt_s;
  const float s = static_cast<float>(std::sin(wt)), c = static_cast<float>(std::cos(wt));
  const float a = static_cast<float>(w == 0.0 ? dt_s : std::sin(wt) / w);
  const float b = static_cast<float>(w == 0.0 ? 0.0 : 2.0 * std::sin(0.5 * wt) * std::sin(0.5 * wt) / w);
  const float dt = static_cast<float>(dt_s);
  const float a_to_v = static_cast<float>(accel_sigma_mps2 * dt_s);
  const float a_to_p = static_cast<float>(0.5 * accel_sigma_mps2 * dt_s * dt_s);
  DrawAccelNormals(key, dt_s);
  moments_valid_ = false;
  const int n = n_;
  const float* __restrict ax = accel_.data();
  const float* __restrict ay = accel_.data() + n;
  const float* __restrict az = accel_.data() + 2 * n;
  float* __restrict x = cur_.x.data();
  float* __restrict y = cur_.y.data();
  float* __restrict z = cur_.z.data();
  float* __restrict vx = cur_.vx.data();
  float* __restrict vy = cur_.vy.data();
  float* __restrict vz = cur_.vz.data();
#pragma omp simd
  for (int i = 0; i < n; ++i) {
    const float ux = vx[i], uy = vy[i];
    x[i] += a * ux - b * uy + a_to_p * ax[i];
    y[i] += b * ux + a * uy + a_to_p * ay[i];
    z[i] += vz[i] * dt + a_to_p * az[i];
    vx[i] = c * ux - s * uy + a_to_v * ax[i];
    vy[i] = s * ux + c * uy + a_to_v * ay[i];
    vz[i] += a_to_v * az[i];
  }
}

}  // namespace localizer::engine
