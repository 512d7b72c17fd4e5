// LocateRequest bytes -> DecodeLocateRequest, as the server decodes a Locate call before
// running it: the config (audio only) and then the block against that config's limits.
#include "fuzz_checks.h"
#include "wire/locate_wire.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace localizer;
  v1::LocateRequest request;
  if (!request.ParseFromArray(data, static_cast<int>(size))) return 0;
  const wire::ConfigPolicy policy = fuzz::FuzzPolicy();
  wire::DecodedLocate decoded;
  const Status status = wire::DecodeLocateRequest(request, policy, &decoded);
  if (!status.ok()) {
    fuzz::CheckRefusal(status, "DecodeLocateRequest");
    return 0;
  }
  FUZZ_CHECK(!request.config().has_detections(), "detection config accepted by Locate");
  fuzz::CheckAcceptedConfig(engine::SessionConfig(decoded.config), policy);
  const wire::BlockLimits limits{static_cast<int>(decoded.config.sensors_m.size()), decoded.config.max_block_samples};
  fuzz::CheckDecodedBlock(request.block(), limits, decoded.block);
  return 0;
}
