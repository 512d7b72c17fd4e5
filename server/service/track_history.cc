#include "server/service/track_history.h"

#include <algorithm>
#include <cmath>

namespace localizer::server {
namespace {

// A ring that grows to `capacity`, then overwrites its oldest entry (at *next). Its storage
// is sized to `capacity` at the first entry: grown by doubling, the 600-point ring would hold
// 1024 slots (and copy itself under the lock on the way), the direction ring 4096 of 2400.
template <typename T>
void Push(const T& value, size_t capacity, std::vector<T>* ring, size_t* next) {
  if (ring->size() < capacity) {
    if (ring->capacity() == 0) ring->reserve(capacity);
    ring->push_back(value);
  } else {
    (*ring)[*next] = value;
    *next = (*next + 1) % capacity;
  }
}

// Its entries oldest first: once full, the oldest sits at `next`.
template <typename T>
std::vector<T> Oldest(const std::vector<T>& ring, size_t next) {
  std::vector<T> out;
  out.reserve(ring.size());
  for (size_t k = 0; k < ring.size(); ++k) out.push_back(ring[(next + k) % ring.size()]);
  return out;
}

}  // namespace

TrackHistory::TrackHistory(size_t capacity) : capacity_(std::max<size_t>(1, capacity)) {}

void TrackHistory::Append(const engine::Estimate& estimate) {
  // Built before taking the lock: the HTTP reader waits only for the copy.
  TrackPoint point;
  if (estimate.initialised) {
    point.frame_index = estimate.frame_index;
    point.t_s = estimate.t_s;
    point.reinitialised = estimate.reinitialised;
    point.source_present = estimate.source_present;
    point.ambiguous = estimate.ambiguous;
    point.far_field = estimate.far_field;
    for (int i = 0; i < 3; ++i) {
      point.position_m[i] = estimate.state(i);
      point.velocity_mps[i] = estimate.state(3 + i);
      // A variance below zero is round-off of a collapsed filter: report zero spread.
      point.position_std_m[i] = std::sqrt(std::max(0.0, estimate.covariance(i, i)));
    }
  }
  PresencePoint presence;
  presence.tested = estimate.presence_threshold > 0.0;
  presence.present = estimate.source_present;
  presence.statistic = estimate.presence_statistic;
  presence.threshold = estimate.presence_threshold;
  presence.ambiguous = estimate.ambiguous;
  presence.modes = estimate.modes;
  presence.far_field = estimate.initialised && estimate.far_field;
  presence.range_sd_m = estimate.range_sd_m;
  std::vector<DirectionPoint> sources;
  sources.reserve(estimate.sources.size());
  for (const engine::SourceEstimate& s : estimate.sources) {
    sources.push_back({estimate.frame_index, estimate.t_s, s.source_id, s.azimuth_rad, s.elevation_rad,
                       s.cone_angle_rad, s.source_present, {s.position_m.x(), s.position_m.y(), s.position_m.z()}});
  }
  MutexLock lock(&mutex_);
  ++frames_;
  if (estimate.source_present) ++present_frames_;
  presence_ = presence;
  for (const DirectionPoint& d : sources) Push(d, capacity_ * kSourcesPerFrame, &directions_, &next_direction_);
  sources_ = std::move(sources);
  model_probabilities_ = estimate.model_probabilities;
  if (estimate.platform) platform_ = estimate.platform;
  if (!estimate.initialised) return;
  ++initialised_frames_;
  Push(point, capacity_, &ring_, &next_);
}

void TrackHistory::SetTargets(const std::vector<engine::tws::TrackReport>& tracks) {
  std::vector<TargetPoint> targets;
  targets.reserve(tracks.size());
  for (const engine::tws::TrackReport& t : tracks) {
    TargetPoint p;
    p.id = t.id;
    p.status = engine::tws::TrackStatusName(t.status);
    for (int i = 0; i < 3; ++i) p.position_m[i] = t.position_m(i);
    targets.push_back(p);
  }
  MutexLock lock(&mutex_);
  ++frames_;
  targets_ = std::move(targets);
}

TrackSnapshot TrackHistory::Snapshot() const {
  TrackSnapshot snapshot;
  snapshot.capacity = capacity_;
  MutexLock lock(&mutex_);
  snapshot.frames = frames_;
  snapshot.initialised_frames = initialised_frames_;
  snapshot.model_probabilities = model_probabilities_;
  snapshot.platform = platform_;
  snapshot.targets = targets_;
  snapshot.presence = presence_;
  snapshot.present_frames = present_frames_;
  snapshot.sources = sources_;
  snapshot.directions = Oldest(directions_, next_direction_);
  snapshot.points = Oldest(ring_, next_);
  return snapshot;
}

}  // namespace localizer::server
