// SampleBlock bytes -> DecodeBlock, as an audio session decodes a Track `block`. The first
// two input bytes choose the limits (the array's sensor count 1..64, samples per channel
// 1..4096); the rest is the message.
#include "fuzz_checks.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace localizer;
  if (size < 2) return 0;
  wire::BlockLimits limits;
  limits.channel_count = 1 + data[0] % 64;
  limits.max_samples_per_channel = 1 + static_cast<int64_t>(data[1]) * 16;
  v1::SampleBlock block;
  if (!block.ParseFromArray(data + 2, static_cast<int>(size - 2))) return 0;
  // Reused between calls as the server reuses it per stream: decode twice into one scratch.
  static wire::DecodedBlock scratch;
  for (int pass = 0; pass < 2; ++pass) {
    std::string reason;
    const Status status = wire::DecodeBlock(block, limits, &scratch, &reason);
    if (!status.ok()) {
      fuzz::CheckRefusal(status, "DecodeBlock");
      FUZZ_CHECK(reason == "channel_count" || reason == "empty" || reason == "oversize" || reason == "bad_samples" ||
                     reason == "non_finite",
                 "reason '" + reason + "'");
      return 0;
    }
    FUZZ_CHECK(reason.empty(), "reason set on success: " + reason);
    fuzz::CheckDecodedBlock(block, limits, scratch);
  }
  return 0;
}
