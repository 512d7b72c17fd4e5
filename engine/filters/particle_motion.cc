// ParticleSet's motion: the prediction step (constant velocity, mean-reverting velocity and
// the coordinated turn), the white acceleration's normals, and the per-particle acceleration
// levels and manoeuvre gains that scale them (particle_set.h). Built with the same 512-bit
// vector option as particle_set.cc (engine/CMakeLists.txt): the draws are compute-bound.
#include <algorithm>
#include <cmath>
#include <cstdint>
#if defined(__AVX512BW__)
#include <immintrin.h>
#endif

#include "engine/core/fast_math.h"
#include "engine/filters/particle_gather.h"
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
    PredictPersistentMotion(dt, a_to_p, a_to_v);
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

// turn_ holds the turn rates, or zeros while only speed changes are on, so that one
// prediction step (PredictPersistentMotion) serves both, whichever was set first.
void ParticleSet::SizeTurnRates() {
  PerParticle(turn_max_radps_ != 0.0f || !speed_change_.empty(), n_, &turn_, &next_turn_);
  std::fill(turn_.begin(), turn_.end(), 0.0f);
}

void ParticleSet::SetTurnRates(double max_radps, double switch_rate_hz) {
  turn_max_radps_ = static_cast<float>(max_radps);
  turn_switch_rate_hz_ = switch_rate_hz;
  SizeTurnRates();
  if (max_radps != 0.0) DrawLevels();
}

void ParticleSet::SetSpeedChanges(double max_mps2, double switch_rate_hz) {
  speed_change_max_mps2_ = static_cast<float>(max_mps2);
  speed_change_switch_rate_hz_ = switch_rate_hz;
  const bool on = max_mps2 != 0.0;
  PerParticle(on, n_, &speed_change_, &next_speed_change_);
  SizeTurnRates();
  if (on) DrawLevels();
}

// A speed change from counters c and c + 1 of `key`: 0 for a share kSpeedHoldShare of the
// draws, uniform in [-max, max] for the others.
static inline float DrawSpeedChange(uint32_t key, uint32_t c, float max_mps2) {
  return UniformFromCounter(key, c) < ParticleSet::kSpeedHoldShare
             ? 0.0f
             : max_mps2 * (2.0f * UniformFromCounter(key, c + 1) - 1.0f);
}

// value[m] <- value[index[m]] for the n slots (resampling), through its scratch.
static void CarryPerParticle(const int* index, int n, std::vector<float>* value, std::vector<float>* scratch) {
  if (value->empty()) return;
  GatherSorted(value->data(), index, n, scratch->data());
  std::swap(*value, *scratch);
}

void ParticleSet::DrawLevels() {
  if (!speed_change_.empty()) {  // off: no key drawn, so the random stream is as before
    const uint32_t key = NextKey();
    for (int i = 0; i < n_; ++i) {
      speed_change_[i] = DrawSpeedChange(key, 2u * static_cast<uint32_t>(i), speed_change_max_mps2_);
    }
  }
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
  CarryPerParticle(index_.data(), n_, &speed_change_, &next_speed_change_);
  CarryPerParticle(index_.data(), n_, &turn_, &next_turn_);
  CarryPerParticle(index_.data(), n_, &gain_, &next_gain_);
}

// Bit k set where flags[k] != 0, k < count <= 64.
static inline uint64_t FlagMask64(const uint8_t* flags, int count) {
#if defined(__AVX512BW__)
  if (count == 64) {
    const __m512i v = _mm512_loadu_si512(flags);
    return _mm512_test_epi8_mask(v, v);
  }
#endif
  uint64_t mask = 0;
  for (int k = 0; k < count; ++k) mask |= static_cast<uint64_t>(flags[k] != 0) << k;
  return mask;
}

// The jumps of each particle's level, turn rate and speed change over dt_s, then its normals
// scaled by its level gain. Each kind has its own switch uniform: level jumps take counters
// past the normals' (2 per particle: the switch, then the new gain), turn rates past the
// levels' and the manoeuvres' (2 per particle), speed changes past the turn rates' (3: the
// switch, then DrawSpeedChange's two). Turn rates and speed changes are drawn for every
// particle and kept where the switch fires (vectorised: no branch per particle); a level's
// new gain needs an exp, so the few level jumps (1 - exp(-rate dt), ~5 % at 1 Hz) are marked
// in a vectorised pass and drawn in a scalar one.
void ParticleSet::DrawPersistentJumps(uint32_t key, double dt_s) {
  const int n = n_;
  const uint32_t level_base = static_cast<uint32_t>(accel_.size());
  const uint32_t turn_base = static_cast<uint32_t>(accel_.size() + 2 * gain_.size() + n_);
  const uint32_t speed_base = turn_base + static_cast<uint32_t>(2 * turn_.size());
  // value[i] takes draw(c) where particle i's switch uniform (counter c = base + stride i)
  // falls below the switch probability; draw reads counters from c + 1.
  const auto redraw = [&](double rate_hz, uint32_t base, uint32_t stride, float* __restrict value, auto draw) {
    const float p = SwitchProbability(rate_hz, dt_s);
#pragma omp simd
    for (int i = 0; i < n; ++i) {
      const uint32_t c = base + stride * static_cast<uint32_t>(i);
      const float drawn = draw(c);
      value[i] = UniformFromCounter(key, c) < p ? drawn : value[i];
    }
  };
  if (!turn_.empty()) {
    const float w_max = turn_max_radps_;
    redraw(turn_switch_rate_hz_, turn_base, 2u, turn_.data(),
           [=](uint32_t c) { return w_max * (2.0f * UniformFromCounter(key, c + 1) - 1.0f); });
  }
  if (!speed_change_.empty()) {
    const float a_max = speed_change_max_mps2_;
    redraw(speed_change_switch_rate_hz_, speed_base, 3u, speed_change_.data(),
           [=](uint32_t c) { return DrawSpeedChange(key, c + 1, a_max); });
  }
  if (gain_.empty()) return;
  const float p = SwitchProbability(level_switch_rate_hz_, dt_s);
  jumps_.resize(static_cast<size_t>(n));
  uint8_t* __restrict jump = jumps_.data();
#pragma omp simd
  for (int i = 0; i < n; ++i) jump[i] = UniformFromCounter(key, level_base + 2u * static_cast<uint32_t>(i)) < p;
  const float lo = log_level_floor_, span = log_level_ceiling_ - log_level_floor_;
  float* __restrict g = gain_.data();
  for (int base = 0; base < n; base += 64) {  // a branch per jump, not per particle
    uint64_t bits = FlagMask64(jump + base, std::min(64, n - base));
    while (bits != 0) {
      const int i = base + __builtin_ctzll(bits);
      bits &= bits - 1;
      g[i] = std::exp(lo + span * UniformFromCounter(key, level_base + 2u * static_cast<uint32_t>(i) + 1));
    }
  }
  float* __restrict a = accel_.data();
#pragma omp simd
  for (int i = 0; i < n; ++i) {
    a[i] *= g[i];
    a[n + i] *= g[i];
    a[2 * n + i] *= g[i];
  }
}

void ParticleSet::DrawAccelNormals(uint32_t key, double dt_s) {
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
  if (!gain_.empty() || !turn_.empty()) DrawPersistentJumps(key, dt_s);
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

// A speed change of a_mps2 over dt on velocity u: the velocity's gain max(0, 1 + a dt / |u|)
// (a particle that slows to a stop stays stopped until its next redraw) and the position
// step's, the mean of the start's 1 and the end's (the step's mean speed over the start's).
// A particle at rest (|u| < 1 mm/s) has no heading to speed up along: both gains stay 1.
static inline void SpeedChangeGains(float a_mps2, float dt, float ux, float uy, float uz, float* position_gain,
                                    float* velocity_gain) {
  const float speed = std::sqrt(ux * ux + uy * uy + uz * uz);
  const float g = speed > 1e-3f ? a_mps2 * dt / speed : 0.0f;
  *velocity_gain = std::max(0.0f, 1.0f + g);
  *position_gain = 0.5f * (1.0f + *velocity_gain);
}

void ParticleSet::PredictPersistentMotion(float dt, float a_to_p, float a_to_v) {
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
  const float* __restrict a = speed_change_.empty() ? nullptr : speed_change_.data();
  if (turn_max_radps_ * dt <= 0.5f) {
    // sin(t)/t and (1 - cos t)/t to t^4 and t^5: float-exact for |t| <= 0.5 (the next terms
    // are below 3e-6 relative), and vectorised where sin and cos per particle would not be.
#pragma omp simd
    for (int i = 0; i < n; ++i) {
      const float t = w[i] * dt, t2 = t * t;
      const float sinc = 1.0f - t2 * (1.0f / 6.0f - t2 * (1.0f / 120.0f));
      const float cosc = t * (0.5f - t2 * (1.0f / 24.0f - t2 * (1.0f / 720.0f)));
      const float s = t * sinc, c = 1.0f - t * cosc;
      const float ux = vx[i], uy = vy[i], uz = vz[i];
      float pg = 1.0f, vg = 1.0f;
      if (a != nullptr) SpeedChangeGains(a[i], dt, ux, uy, uz, &pg, &vg);
      x[i] += pg * dt * (sinc * ux - cosc * uy) + a_to_p * ax[i];
      y[i] += pg * dt * (cosc * ux + sinc * uy) + a_to_p * ay[i];
      z[i] += pg * dt * uz + a_to_p * az[i];
      vx[i] = vg * (c * ux - s * uy) + a_to_v * ax[i];
      vy[i] = vg * (s * ux + c * uy) + a_to_v * ay[i];
      vz[i] = vg * uz + a_to_v * az[i];
    }
    return;
  }
  for (int i = 0; i < n; ++i) {  // a long step (a gap in the frames): exact, per particle
    const double t = static_cast<double>(w[i]) * dt;
    const double s = std::sin(t), c = std::cos(t);
    const double sinc = t == 0.0 ? 1.0 : s / t, cosc = t == 0.0 ? 0.0 : (1.0 - c) / t;
    const double ux = vx[i], uy = vy[i];
    float pg = 1.0f, vg = 1.0f;
    if (a != nullptr) SpeedChangeGains(a[i], dt, vx[i], vy[i], vz[i], &pg, &vg);
    x[i] += pg * static_cast<float>(dt * (sinc * ux - cosc * uy)) + a_to_p * ax[i];
    y[i] += pg * static_cast<float>(dt * (cosc * ux + sinc * uy)) + a_to_p * ay[i];
    z[i] += pg * dt * vz[i] + a_to_p * az[i];
    vx[i] = vg * static_cast<float>(c * ux - s * uy) + a_to_v * ax[i];
    vy[i] = vg * static_cast<float>(s * ux + c * uy) + a_to_v * ay[i];
    vz[i] = vg * vz[i] + a_to_v * az[i];
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
