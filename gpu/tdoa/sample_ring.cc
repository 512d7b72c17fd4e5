#include "gpu/tdoa/sample_ring.h"

#include <string>
#include <utility>

namespace localizer::gpu {

StatusOr<SampleRing> SampleRing::Create(int channels, int capacity) {
  if (channels < 1 || capacity < 1) {
    return InvalidArgument("sample ring of " + std::to_string(channels) + " channels x " + std::to_string(capacity) +
                           " samples; both must be >= 1");
  }
  auto memory = DeviceBuffer<float>::Allocate(static_cast<std::size_t>(channels) * capacity);
  if (!memory.ok()) return memory.status();
  return SampleRing(std::move(memory).value(), channels, capacity);
}

void SampleRing::Advance(int samples) {
  if (!valid_) total_ = 0;
  total_ += samples;
  valid_ = true;
}

}  // namespace localizer::gpu
