#include "gpu/filters/step_builder.h"

#include <cmath>
#include <limits>
#include <string>

#include "engine/core/normal_quantile.h"
#include "engine/filters/gcc_upsampling.h"
#include "engine/filters/particle_set.h"
#include "gpu/filters/pf_math.cuh"

namespace localizer::gpu::pf {

StatusOr<SessionConfig> MakeSessionConfig(const engine::ArrayGeometry& array,
                                          const engine::ParticleFilterOptions& options) {
  LOCALIZER_RETURN_IF_ERROR(options.Validate());
  if (array.pair_count() > kMaxPairs) {
    return InvalidArgument("the GPU particle filter takes at most " + std::to_string(kMaxPairs + 1) +
                           " sensors; the array has " + std::to_string(array.sensor_count()));
  }
  SessionConfig config;
  config.options = options;
  config.pairs = array.pair_count();
  const engine::Vec3 origin = array.centroid_m();
  for (int a = 0; a < 3; ++a) config.origin_m[a] = origin(a);
  const auto relative = [&](int sensor, float out[3]) {
    const engine::Vec3& m = array.sensor_m(sensor);
    for (int a = 0; a < 3; ++a) out[a] = static_cast<float>(m(a) - origin(a));
  };
  relative(array.reference_sensor(), config.reference);
  for (int p = 0; p < config.pairs; ++p) relative(array.sensor_of_pair(p), config.pair_sensor[p]);
  config.inv_c = static_cast<float>(1.0 / array.sound_speed_mps());
  if (options.kernel_scale > 0.0) {
    config.kernel_h = engine::KernelBandwidth(options.kernel_scale, options.particles);
    config.kernel_a = engine::KernelShrinkage(config.kernel_h);
  }
  if (options.manoeuvre_share > 0.0) {
    config.manoeuvre_z = static_cast<float>(engine::NormalQuantile(options.manoeuvre_share));
  } else {
    config.manoeuvre_z = -std::numeric_limits<float>::infinity();
  }
  const engine::ManoeuvreGains gains = engine::ManoeuvreGainsFor(options.manoeuvre_share, options.manoeuvre_scale);
  config.quiet_gain = static_cast<float>(gains.quiet);
  config.manoeuvre_gain = static_cast<float>(gains.manoeuvre);
  return config;
}

Status FillSessionStep(const SessionConfig& config, const StepInputs& in, std::vector<float>* gcc, SessionStep* step) {
  const engine::ParticleFilterOptions& o = config.options;
  if (std::isnan(in.dt_s) || std::isinf(in.dt_s)) {
    return InvalidArgument("dt_s must be finite, got " + std::to_string(in.dt_s));
  }
  step->pairs = config.pairs;
  step->do_predict = in.dt_s > 0.0 ? 1 : 0;
  step->dt = static_cast<float>(in.dt_s);
  step->a_to_v = static_cast<float>(o.accel_noise_mps2 * in.dt_s);
  step->a_to_p = static_cast<float>(0.5 * o.accel_noise_mps2 * in.dt_s * in.dt_s);
  step->manoeuvre_z = config.manoeuvre_z;
  step->quiet_gain = config.quiet_gain;
  step->manoeuvre_gain = config.manoeuvre_gain;
  for (int a = 0; a < 3; ++a) step->reference[a] = config.reference[a];
  step->inv_c = config.inv_c;
  step->inv_dof = static_cast<float>(1.0 / o.peak_dof);
  step->half_dof_plus_1 = static_cast<float>(0.5 * (o.peak_dof + 1.0));
  step->resample_below = o.resample_threshold * o.particles;
  step->kernel = o.kernel_scale > 0.0 ? 1 : 0;
  step->kernel_h = config.kernel_h;
  step->kernel_a = config.kernel_a;
  step->seed = o.seed;
  step->do_update = 0;
  for (int p = 0; p < kMaxPairs; ++p) {
    PairParams& pp = step->pair[p];
    pp = PairParams{};
    pp.gcc_offset = -1;
    if (p < config.pairs) {
      for (int a = 0; a < 3; ++a) pp.sensor[a] = config.pair_sensor[p][a];
    }
  }
  const engine::Measurement* m = in.measurement;
  if (m == nullptr) return Status::Ok();
  if (static_cast<int>(m->pairs.size()) != config.pairs) {
    return InvalidArgument("measurement has " + std::to_string(m->pairs.size()) + " pairs; the array has " +
                           std::to_string(config.pairs));
  }
  if (in.used == nullptr || in.sigmas_s == nullptr) {
    return InvalidArgument("a step with a measurement needs used and sigmas_s per pair");
  }
  std::vector<float> fine;
  for (int p = 0; p < config.pairs; ++p) {
    if (!in.used[p]) continue;
    const engine::PairMeasurement& pm = m->pairs[p];
    const double sigma_s = in.sigmas_s[p];
    if (!std::isfinite(pm.delay_s)) {
      return InvalidArgument("pair " + std::to_string(p) + " delay_s is not finite");
    }
    if (!(sigma_s > 0.0) || !std::isfinite(sigma_s)) {
      return InvalidArgument("pair " + std::to_string(p) + " sigma_s must be finite and > 0, got " +
                             std::to_string(sigma_s));
    }
    PairParams& pp = step->pair[p];
    pp.used = 1;
    pp.delay_s = static_cast<float>(pm.delay_s);
    pp.half_delay_s = 0.5f * pp.delay_s;
    pp.inv_sigma = static_cast<float>(1.0 / sigma_s);
    // Motion blur widens the peak likelihood as the engine's filter does (particle_set.h).
    if (o.likelihood != engine::Likelihood::kGcc) {
      pp.blur_var_s2 =
          static_cast<float>(engine::MotionBlurVariance(o.motion_blur, m->window_time_var_s2, pm.peak_snr));
    }
    const bool use_gcc = o.likelihood == engine::Likelihood::kGcc && pm.gcc.size() >= 4;
    if (use_gcc) {
      if (!(m->sample_rate_hz > 0.0) || !std::isfinite(m->sample_rate_hz)) {
        return InvalidArgument("measurement sample_rate_hz must be > 0 for the GCC likelihood, got " +
                               std::to_string(m->sample_rate_hz));
      }
      engine::UpsampleGcc(pm.gcc, engine::kGccUpsampling, &fine);
      pp.gcc_offset = static_cast<int>(gcc->size());
      gcc->insert(gcc->end(), fine.begin(), fine.end());
      pp.lag_scale = static_cast<float>(m->sample_rate_hz * engine::kGccUpsampling);
      pp.lag0 = static_cast<float>(pm.first_lag_samples * engine::kGccUpsampling);
      pp.last_lag = static_cast<float>(fine.size() - 3) - 1e-3f;
      pp.gcc_gain = static_cast<float>(
          engine::GccGain(fine, sigma_s * m->sample_rate_hz * engine::kGccUpsampling, o.gcc_sharpness));
    }
    step->do_update = 1;
  }
  return Status::Ok();
}

}  // namespace localizer::gpu::pf
