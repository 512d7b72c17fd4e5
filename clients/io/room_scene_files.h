// A room scene on disk: the scene file `localizer-cli simulate --room` reads, and the files
// it writes, so users can rehearse their own array in their own room (issue 18).
//
// Scene file (JSON; unknown fields are refused, every error names the file and the field):
//   {
//     "room": {"size_m": [6, 5, 3], "rt60_s": 0.4},   required; rt60_s 0: free field (the
//                                                     direct path only), up to 2 s
//     "array_position_m": [3, 2.5, 1],                where the array file's origin sits in
//                                                     the room (default [0, 0, 0])
//     "sample_rate_hz": 16000,                        default 16000
//     "duration_s": 20,                               default 10, up to 600
//     "noise_db": -20,                                sensor noise power against a level-0
//                                                     source's direct sound at 1 m (default -20)
//     "sources": [                                    1 to 16, fixed
//       {"position_m": [4.5, 3.2, 1.4],               required, inside the room
//        "signal": "bursts",                          broadband | tones | bursts (default) | speech
//        "band_hz": [100, 7000],                      default [100, min(7000, fs / 2)]
//        "level_db": 0,                               default 0
//        "on_s": [0.4, 1.5], "off_s": [0.2, 1.0],     bursts' (and speech's) on and off durations (defaults)
//        "start_s": 0, "stop_s": 20}                  when it may sound (default: throughout)
//     ]
//   }
// The sound speed is the array file's. engine/sim/room_scene.h says how signals are made.
//
// What is written in DIR:
//   signals.wav   float32, channel k = sensor k
//   array.json    the array file with its sensors moved into the room (array_position_m
//                 added; a source_plane's point alike) and sample_rate_hz: `track` on it
//                 reports in room coordinates
//   sources.csv   source,signal,x_m,y_m,z_m,range_m,azimuth_rad,elevation_rad,cone_angle_rad
//                 (seen from the array's centroid; azimuth = atan2(y, x), elevation towards
//                 +z; the cone angle to a linear array's axis, else empty)
//   sounding.csv  source,on_s,off_s: when each source is heard at the array's centroid
//                 (its sounding intervals delayed by the direct path's travel)
#pragma once

#include <cstdint>
#include <optional>
#include <string>

#include "clients/io/array_json.h"
#include "engine/core/status.h"
#include "engine/sim/room_scene.h"

namespace localizer::io {

struct RoomSceneFile {
  engine::RoomScene scene;
  engine::Vec3 array_position_m = engine::Vec3::Zero();
};

// `source` names the text in messages (usually its path). The room's sound speed is set
// later, from the array file.
StatusOr<RoomSceneFile> ParseRoomSceneJson(const std::string& text, const std::string& source);
StatusOr<RoomSceneFile> ReadRoomSceneJson(const std::string& path);

struct RoomSimulationFiles {
  std::string wav_path, array_path, sources_path, sounding_path;
  int64_t samples_per_channel = 0;
};

// Renders the scene for the array (the array file's sensors moved to array_position_m,
// its sound speed for the room) with `seed`, the duration overridden when given (> 0),
// and writes the four files into `dir` (created if missing). INVALID_ARGUMENT naming the
// field for a scene that does not fit the array (a sensor outside the room, ...).
StatusOr<RoomSimulationFiles> SimulateRoomScene(const RoomSceneFile& file, const ArrayFile& array, uint64_t seed,
                                                std::optional<double> duration_s, const std::string& dir);

}  // namespace localizer::io
