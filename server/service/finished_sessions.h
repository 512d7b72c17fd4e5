// FinishedSessions: the last sessions that ended, kept for the live view (GET /sessions lists
// them under "finished", GET / draws them and can replay their tracks), so a session that
// ended before anyone looked -- a `--rate max` run lasts milliseconds -- can still be seen.
//
// Each entry is the session as GET /sessions rendered it when it ended (its track included:
// the TrackHistory's last fixes), never the session itself, so its engine memory is freed at
// once. Bounded: at most `keep` entries (the oldest goes first) and each for at most
// `keep_s`; an entry's size is bounded by the track history's capacity (a few hundred kB).
//
// Thread-safe (one mutex of its own, never held while calling out).
#pragma once

#include <chrono>
#include <cstddef>
#include <deque>
#include <string>
#include <vector>

#include "server/sync/mutex.h"

namespace localizer::server {

using Clock = std::chrono::steady_clock;  // as the session host's (inbox.h)

struct FinishedSession {
  std::string session_json;  // one JSON object, as in GET /sessions' "sessions"
  std::string reason;        // "finished", "closed", "expired", "idle", ... (the closed-sessions metric's)
  Clock::time_point finished_at;
};

class FinishedSessions final {
 public:
  static constexpr size_t kMaxKeep = 256;  // --live-keep-finished's ceiling

  // keep 0 keeps nothing (Add is a no-op); keep_s <= 0 likewise.
  FinishedSessions(size_t keep, double keep_s);
  FinishedSessions(const FinishedSessions&) = delete;
  FinishedSessions& operator=(const FinishedSessions&) = delete;

  bool enabled() const { return keep_ > 0 && keep_s_ > 0.0; }
  void Add(FinishedSession session) EXCLUDES(mutex_);
  // The entries still kept at `now`, most recently finished first (expired ones are dropped).
  std::vector<FinishedSession> Snapshot(Clock::time_point now) EXCLUDES(mutex_);

 private:
  void DropExpired(Clock::time_point now) REQUIRES(mutex_);

  const size_t keep_;
  const double keep_s_;
  mutable Mutex mutex_;
  std::deque<FinishedSession> entries_ GUARDED_BY(mutex_);  // oldest first
};

}  // namespace localizer::server
