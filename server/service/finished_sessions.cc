#include "server/service/finished_sessions.h"

#include <algorithm>
#include <utility>

namespace localizer::server {

FinishedSessions::FinishedSessions(size_t keep, double keep_s) : keep_(std::min(keep, kMaxKeep)), keep_s_(keep_s) {}

void FinishedSessions::Add(FinishedSession session) {
  if (!enabled()) return;
  MutexLock lock(&mutex_);
  DropExpired(session.finished_at);
  entries_.push_back(std::move(session));
  while (entries_.size() > keep_) entries_.pop_front();
}

std::vector<FinishedSession> FinishedSessions::Snapshot(Clock::time_point now) {
  MutexLock lock(&mutex_);
  DropExpired(now);
  return {entries_.rbegin(), entries_.rend()};
}

void FinishedSessions::DropExpired(Clock::time_point now) {
  const auto keep_for = std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(keep_s_));
  while (!entries_.empty() && now - entries_.front().finished_at > keep_for) entries_.pop_front();
}

}  // namespace localizer::server
