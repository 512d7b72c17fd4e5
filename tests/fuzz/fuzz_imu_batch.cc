// ImuBatch bytes -> DecodeImuBatch, as a moving-array session decodes a Track `imu`.
#include "fuzz_checks.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace localizer;
  v1::ImuBatch batch;
  if (!batch.ParseFromArray(data, static_cast<int>(size))) return 0;
  auto decoded = wire::DecodeImuBatch(batch);
  if (!decoded.ok()) {
    fuzz::CheckRefusal(decoded.status(), "DecodeImuBatch");
    return 0;
  }
  fuzz::CheckDecodedImu(batch, *decoded);
  return 0;
}
