// SessionConfig bytes -> ConfigFromProto, as the server opens a session (Track's `open`).
// An accepted config must satisfy the policy and the engine's validation and round-trip
// through its effective config; a refused one is INVALID_ARGUMENT with a printable message.
#include "fuzz_checks.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace localizer;
  v1::SessionConfig proto;
  if (!proto.ParseFromArray(data, static_cast<int>(size))) return 0;
  const wire::ConfigPolicy policy = fuzz::FuzzPolicy();
  auto config = wire::ConfigFromProto(proto, policy);
  if (!config.ok()) {
    fuzz::CheckRefusal(config.status(), "ConfigFromProto");
    return 0;
  }
  fuzz::CheckAcceptedConfig(*config, policy);
  // Locate's variant refuses exactly the detection configs and accepts the rest alike.
  auto audio = wire::AudioConfigFromProto(proto, policy);
  FUZZ_CHECK(audio.ok() == std::holds_alternative<engine::AudioSessionConfig>(*config),
             audio.ok() ? "detection config accepted as audio" : audio.status().ToString());
  return 0;
}
