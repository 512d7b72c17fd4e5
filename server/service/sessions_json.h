// The JSON document served at GET /sessions for the live web view (live_page.h) and for
// scripts: every session the registry holds, with its array and its recent track.
//
//   {"version": "...", "sessions_total": N, "track_sessions_max": 32,
//    "sessions": [{"id", "label", "backend", "filter_type", "attached",
//                  "sensors_m": [[x, y, z], ...], "reference_sensor",
//                  "sample_rate_hz", "sound_speed_mps", "blocks", "frames",
//                  "initialised_frames", "age_s", "idle_s",
//                  "track_capacity", "track_included",
//                  "track": [{"frame", "t_s", "position_m": [x, y, z],
//                             "velocity_mps": [...], "position_std_m": [...],
//                             "reinitialised"}, ...],              // oldest first
//                  "model_probabilities": [{"model", "probability"}, ...]}, ...],
//    "finished": [{"finished_ago_s", "reason", "session": {... as above, with its track}}, ...]}
//
// Sessions are listed oldest first. Only the first kMaxTrackSessions carry their track
// ("track_included": false and an empty track for the rest), so the document stays under
// a few megabytes even with a thousand sessions. Numbers that are not finite are written
// as null (JSON has no NaN); label bytes that are not UTF-8 become U+FFFD. "finished" lists
// the sessions that ended (finished_sessions.h), most recent first, each as it was rendered
// when it ended (FinishedSessionJson), with why it ended ("finished": the client half-closed
// and every block was answered; "closed", "expired", "idle", ...: the registry's reasons).
#pragma once

#include <cstddef>
#include <memory>
#include <string>
#include <vector>

#include "server/service/finished_sessions.h"
#include "server/service/session_host.h"

namespace localizer::server {

inline constexpr size_t kMaxTrackSessions = 32;

// Thread-safe (takes each host's locks in turn, never two at once).
std::string SessionsJson(const std::vector<std::shared_ptr<SessionHost>>& hosts, Clock::time_point now, double ttl_s,
                         const std::vector<FinishedSession>& finished = {},
                         size_t max_track_sessions = kMaxTrackSessions);

// One session's object with its track, from `info` (the host's counters, taken by the caller:
// a session that finishes is rendered under its own lock, SessionHost::Info would take it
// again). Takes the track history's lock only.
std::string FinishedSessionJson(const SessionHost& host, const v1::SessionInfo& info);

}  // namespace localizer::server
