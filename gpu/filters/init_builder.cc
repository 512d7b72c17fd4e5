#include "gpu/filters/init_builder.h"

#include <cmath>

namespace localizer::gpu::pf {

Status MakeGaussianInit(const SessionConfig& config, const engine::Vec6& mean, const engine::Mat6& root,
                        unsigned long long draw, GaussianInit* out) {
  if (!mean.allFinite() || !root.allFinite()) return InvalidArgument("initial mean or root is not finite");
  GaussianInit init{};
  for (int r = 0; r < 6; ++r) {
    init.mean[r] = static_cast<float>(mean(r) - (r < 3 ? config.origin_m[r] : 0.0));
    for (int c = 0; c < 6; ++c) init.root[r * 6 + c] = static_cast<float>(root(r, c));
  }
  init.seed = config.options.seed;
  init.draw = draw;
  *out = init;
  return Status::Ok();
}

Status MakeRegionInit(const SessionConfig& config, const engine::Vec3& min_m, const engine::Vec3& max_m,
                      double speed_sigma_mps, unsigned long long draw, RegionInit* out) {
  if (!min_m.allFinite() || !max_m.allFinite() || (max_m - min_m).minCoeff() < 0.0 || !(speed_sigma_mps >= 0.0) ||
      !std::isfinite(speed_sigma_mps)) {
    return InvalidArgument("initial region must be a finite box with min <= max and speed sigma >= 0");
  }
  RegionInit init{};
  for (int a = 0; a < 3; ++a) {
    init.lo[a] = static_cast<float>(min_m(a) - config.origin_m[a]);
    init.span[a] = static_cast<float>(max_m(a) - min_m(a));
  }
  init.speed_sigma = static_cast<float>(speed_sigma_mps);
  init.seed = config.options.seed;
  init.draw = draw;
  *out = init;
  return Status::Ok();
}

void InitPlan::Add(InitTask task) {
  task.first_block = blocks();
  block_task.insert(block_task.end(), static_cast<std::size_t>(task.slot.blocks), static_cast<int>(tasks.size()));
  tasks.push_back(task);
}

}  // namespace localizer::gpu::pf
