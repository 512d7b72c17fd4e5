// Host side of the particle bank's initialisation: the engine's belief or region turned into
// the float parameters the kernels read (relative to the array centroid, as the slot's
// particles are), and the plan of one batched launch (pf_kernels.h, LaunchInitialiseBatch):
// which slots, with which parameters, and which grid block serves which slot. Plain C++, no
// device calls: tested without a GPU (tests/gpu/pf_init_builder_test.cc).
//
// Why batched: sessions that start (or restart after losing their source) together used to
// initialise one by one, each a launch and a synchronisation under the bank's lock, so a burst
// of starts queued behind itself and lifted every session's frame latency
// (BENCHMARKS.md "GPU backend"); one launch for all of them costs about what one did.
#pragma once

#include <vector>

#include "engine/core/status.h"
#include "engine/core/types.h"
#include "gpu/filters/pf_kernels.h"
#include "gpu/filters/step_builder.h"

namespace localizer::gpu::pf {

// x = mean + root z for a slot of `config`, with Philox window `draw`. INVALID_ARGUMENT
// ("initial mean or root is not finite") for non-finite inputs.
Status MakeGaussianInit(const SessionConfig& config, const engine::Vec6& mean, const engine::Mat6& root,
                        unsigned long long draw, GaussianInit* out);

// Position uniform in [min_m, max_m], velocity ~ N(0, speed_sigma_mps^2 I3). INVALID_ARGUMENT
// unless the box is finite with min <= max and speed_sigma_mps is finite and >= 0.
Status MakeRegionInit(const SessionConfig& config, const engine::Vec3& min_m, const engine::Vec3& max_m,
                      double speed_sigma_mps, unsigned long long draw, RegionInit* out);

// One batched launch: tasks in the order added; block_task[b] is the task grid block b
// serves; a task's blocks are contiguous from its first_block, slot.blocks of them.
struct InitPlan {
  std::vector<InitTask> tasks;
  std::vector<int> block_task;

  // Appends `task` (its first_block is set here).
  void Add(InitTask task);
  void Clear() {
    tasks.clear();
    block_task.clear();
  }
  int blocks() const { return static_cast<int>(block_task.size()); }
};

}  // namespace localizer::gpu::pf
