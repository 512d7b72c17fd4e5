// Room scene text -> ParseRoomSceneJson (what `simulate --room` reads), then the scene's
// Validate for a 2-sensor array in the room's corner region. Parsing never crashes; a refusal
// is INVALID_ARGUMENT naming the file; an accepted scene lists at most 16 sources with
// finite positions, and Validate answers OK or INVALID_ARGUMENT (rendering is not run: its
// cost is bounded by Validate, and a fuzzer would spend its time there).
#include "clients/io/room_scene_files.h"
#include "fuzz_checks.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace localizer;
  const std::string text(reinterpret_cast<const char*>(data), size);
  auto file = io::ParseRoomSceneJson(text, "scene.json");
  if (!file.ok()) {
    FUZZ_CHECK(file.status().code() == StatusCode::kInvalidArgument, file.status().ToString());
    FUZZ_CHECK(file.status().message().rfind("scene.json", 0) == 0, file.status().message());
    return 0;
  }
  FUZZ_CHECK(file->scene.sources.size() <= 16, std::to_string(file->scene.sources.size()));
  for (const engine::RoomSceneSource& s : file->scene.sources) FUZZ_CHECK(s.position_m.allFinite(), "position");
  FUZZ_CHECK(file->array_position_m.allFinite(), "array position");
  const std::vector<engine::Vec3> sensors = {file->array_position_m + engine::Vec3(0.1, 0.1, 0.1),
                                             file->array_position_m + engine::Vec3(0.2, 0.1, 0.1)};
  const Status valid = file->scene.Validate(sensors);
  FUZZ_CHECK(valid.ok() || valid.code() == StatusCode::kInvalidArgument, valid.ToString());
  return 0;
}
