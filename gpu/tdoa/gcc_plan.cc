#include "gpu/tdoa/gcc_plan.h"

#include <functional>

#include "engine/tdoa/peak_math.h"

namespace localizer::gpu {

std::string GccBatchKey::ToString() const {
  return "frame_samples=" + std::to_string(frame_samples) + " fft_size=" + std::to_string(fft_size) +
         " channels=" + std::to_string(channels);
}

std::size_t GccBatchKeyHash::operator()(const GccBatchKey& key) const {
  std::size_t h = std::hash<int>()(key.frame_samples);
  h = h * 1000003u ^ std::hash<int>()(key.fft_size);
  h = h * 1000003u ^ std::hash<int>()(key.channels);
  return h;
}

StatusOr<GccPlan> GccPlan::Create(const engine::ArrayGeometry& array, const engine::GccOptions& options) {
  auto layout = engine::ComputeGccLayout(array, options);
  if (!layout.ok()) return layout.status();
  if (options.weighting == engine::Weighting::kPhatCoherence) {
    return InvalidArgument(
        "weighting phat-coherence learns from frame to frame and is not computed by the GPU "
        "batch (the GPU backend measures such sessions on the CPU)");
  }
  if (options.weighting == engine::Weighting::kPhatShare) {
    return InvalidArgument(
        "weighting phat-share reads every channel's spectrum before weighing a pair and is not "
        "computed by the GPU batch (the GPU backend measures such sessions on the CPU)");
  }
  GccPlan plan;
  plan.options_ = options;
  plan.layout_ = std::move(layout).value();
  plan.reference_sensor_ = array.reference_sensor();
  for (int p = 0; p < array.pair_count(); ++p) {
    plan.sensor_of_pair_.push_back(array.sensor_of_pair(p));
    if (options.keep_gcc)
      plan.gcc_floats_ += 2 * static_cast<std::size_t>(plan.layout_.max_lag_samples[p] + engine::kPeakHalfWidth) + 1;
  }
  return plan;
}

}  // namespace localizer::gpu
