#include "engine/pipeline/locate.h"

#include <chrono>
#include <cmath>
#include <string>

#include "engine/tdoa/gcc_phat.h"

namespace localizer::engine {
namespace {

constexpr int kMinLocateSamples = 64;

Status ValidateLocateBlock(const BlockView& block, int channels, int64_t max_samples) {
  if (block.channel_count != channels) {
    return InvalidArgument("channel_count is " + std::to_string(block.channel_count) + "; the array has " +
                           std::to_string(channels) + " sensors");
  }
  if (block.samples_per_channel < kMinLocateSamples || block.samples_per_channel > max_samples) {
    return InvalidArgument("samples per channel is " + std::to_string(block.samples_per_channel) + "; locate needs [" +
                           std::to_string(kMinLocateSamples) + ", " + std::to_string(max_samples) + "]");
  }
  const int64_t total = block.samples_per_channel * channels;
  for (int64_t i = 0; i < total; ++i) {
    if (!std::isfinite(block.samples[i])) {
      return InvalidArgument("samples[" + std::to_string(i) + "] (channel " +
                             std::to_string(i / block.samples_per_channel) + ") is not finite");
    }
  }
  return Status::Ok();
}

}  // namespace

StatusOr<LocateResult> Locate(const AudioSessionConfig& config, const BlockView& block) {
  if (block.samples == nullptr) return InvalidArgument("samples is empty");
  AudioSessionConfig checked = config;
  checked.frame_samples =
      static_cast<int>(std::min<int64_t>(std::max<int64_t>(block.samples_per_channel, kMinLocateSamples), 1 << 20));
  checked.hop_samples = checked.frame_samples;
  LOCALIZER_RETURN_IF_ERROR(checked.Validate());
  auto array = ArrayGeometry::Create(checked.sensors_m, checked.sound_speed_mps, checked.reference_sensor);
  if (!array.ok()) {
    return InvalidArgument("array.sensors_m: " + array.status().message() +
                           "; Locate gives a position (for the directions of a planar or linear array, open a "
                           "session: localization direction)");
  }
  LOCALIZER_RETURN_IF_ERROR(ValidateLocateBlock(block, array->sensor_count(), checked.max_block_samples));

  GccOptions gcc = checked.GccOptionsFor();
  gcc.keep_gcc = false;  // no tracker reads it
  auto estimator = GccPhatEstimator::Create(*array, gcc);
  if (!estimator.ok()) return estimator.status();

  LocateResult result;
  const auto start = std::chrono::steady_clock::now();
  const double t_mid_s = 0.5 * (checked.frame_samples - 1) / checked.sample_rate_hz;
  LOCALIZER_RETURN_IF_ERROR((*estimator)->Estimate(block.samples, checked.frame_samples, t_mid_s, &result.measurement));
  result.tdoa_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();

  const auto pairs = static_cast<Eigen::Index>(result.measurement.pairs.size());
  Eigen::VectorXd delays(pairs);
  for (Eigen::Index p = 0; p < pairs; ++p) delays(p) = result.measurement.pairs[p].delay_s;
  const double floor_s = 1.0 / (checked.sample_rate_hz * std::sqrt(12.0));
  MultilaterationOptions options;
  options.tdoa_sigma_s = floor_s;
  auto fix = Multilaterate(*array, delays, options);
  if (!fix.ok() || !fix->converged || !fix->position_m.allFinite()) return result;
  // Rescale the covariance from the floor to the std the residuals show, when larger.
  const double dof = static_cast<double>(pairs) - 3.0;
  const double sigma_s =
      dof > 0.0 ? std::max(floor_s, fix->rms_residual_s * std::sqrt(static_cast<double>(pairs) / dof)) : floor_s;
  fix->covariance_m2 *= (sigma_s * sigma_s) / (floor_s * floor_s);
  result.fix = *fix;
  result.fix_found = true;
  return result;
}

}  // namespace localizer::engine
