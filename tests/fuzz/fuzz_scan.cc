// Scan bytes -> DecodeScan, as a detection session decodes a Track `scan`.
#include "fuzz_checks.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace localizer;
  v1::Scan scan;
  if (!scan.ParseFromArray(data, static_cast<int>(size))) return 0;
  auto decoded = wire::DecodeScan(scan);
  if (!decoded.ok()) {
    fuzz::CheckRefusal(decoded.status(), "DecodeScan");
    return 0;
  }
  fuzz::CheckDecodedScan(scan, *decoded);
  return 0;
}
