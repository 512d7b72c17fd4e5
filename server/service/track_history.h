// TrackHistory: a session's recent estimated track for the live web view (GET /sessions).
//
// A bounded ring of the last `capacity` initialised positions (with their frame instant
// t_s) and the latest estimate's model probabilities, source presence and ambiguity; for
// direction sessions, a ring of the last kSourcesPerFrame x capacity (frame, source)
// directions and the latest frame's sources. Frames before the tracker's first
// fix carry no position and are only counted. Memory is fixed once the ring is full
// (capacity x 40 bytes), so a long session costs no more than a short one.
//
// Thread-safety: Append runs on the session's worker thread while Snapshot runs on an HTTP
// thread; a mutex of its own (never held while calling out) keeps them apart without
// touching the session host's lock, so a slow page read never stalls the stream.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <vector>

#include "engine/core/estimate.h"
#include "engine/tws/track_report.h"
#include "server/sync/mutex.h"

namespace localizer::server {

struct TrackPoint {
  uint64_t frame_index = 0;
  double t_s = 0.0;               // the estimate's reception instant (engine::Estimate::t_s)
  double position_m[3] = {};      // x, y, z
  double velocity_mps[3] = {};    // vx, vy, vz
  double position_std_m[3] = {};  // square roots of the covariance's position diagonal
  bool reinitialised = false;     // the tracker restarted from a new fix at this frame
  bool source_present = false;    // a source was heard at this frame (else a prediction)
  bool ambiguous = false;         // several position hypotheses fit this frame
  bool far_field = false;         // the frame could not bound the range (engine::Estimate::far_field)
};

// A direction session's source at one frame (engine::SourceEstimate); angles NaN where the
// array cannot observe them (azimuth and elevation of a line, the cone angle otherwise).
struct DirectionPoint {
  uint64_t frame_index = 0;
  double t_s = 0.0;
  uint64_t source_id = 0;
  double azimuth_rad = 0.0;
  double elevation_rad = 0.0;
  double cone_angle_rad = 0.0;
  bool source_present = false;  // heard at this frame (else a prediction)
  // Positions from a planar or linear array: where the frame bounded the range, else NaN.
  double position_m[3] = {engine::SourceEstimate::kNan, engine::SourceEstimate::kNan, engine::SourceEstimate::kNan};
};

// A detection session's target after its latest scan.
struct TargetPoint {
  uint64_t id = 0;
  const char* status = "";  // "tentative" | "confirmed" | "coasting"
  double position_m[3] = {};
};

// An audio session's source presence, ambiguity and range observability at its latest frame
// (engine::Estimate::source_present, ...); `tested` is false when the engine ran no
// presence test (threshold 0).
struct PresencePoint {
  bool tested = false;
  bool present = false;
  double statistic = 0.0;
  double threshold = 0.0;
  bool ambiguous = false;
  int modes = 0;
  bool far_field = false;
  double range_sd_m = 0.0;
};

struct TrackSnapshot {
  std::vector<TrackPoint> points;                             // oldest first, at most capacity
  std::vector<engine::ModelProbability> model_probabilities;  // of the latest estimate
  std::optional<engine::PlatformAttitude> platform;           // moving arrays: the latest pose
  std::vector<TargetPoint> targets;                           // detection sessions: the latest scan's tracks
  std::vector<DirectionPoint> directions;                     // direction sessions: oldest first, at most
                                                              // kSourcesPerFrame x capacity
  std::vector<DirectionPoint> sources;                        // direction sessions: the latest frame's
  std::optional<PresencePoint> presence;                      // audio sessions: the latest frame's; none before it
  uint64_t present_frames = 0;                                // frames that held a source
  uint64_t frames = 0;                                        // estimates appended, initialised or not (detection
                                                              // sessions: scans)
  uint64_t initialised_frames = 0;
  size_t capacity = 0;
};

class TrackHistory final {
 public:
  static constexpr size_t kDefaultCapacity = 600;
  // Direction sessions keep capacity x this many (frame, source) points.
  static constexpr size_t kSourcesPerFrame = 4;

  explicit TrackHistory(size_t capacity = kDefaultCapacity);  // capacity 0 is taken as 1
  TrackHistory(const TrackHistory&) = delete;
  TrackHistory& operator=(const TrackHistory&) = delete;

  void Append(const engine::Estimate& estimate) EXCLUDES(mutex_);
  // Detection sessions: the tracks after the latest scan replace the previous ones.
  void SetTargets(const std::vector<engine::tws::TrackReport>& tracks) EXCLUDES(mutex_);
  TrackSnapshot Snapshot() const EXCLUDES(mutex_);
  size_t capacity() const { return capacity_; }

 private:
  const size_t capacity_;
  mutable Mutex mutex_;
  std::vector<TrackPoint> ring_ GUARDED_BY(mutex_);  // grows to capacity_, then wraps
  size_t next_ GUARDED_BY(mutex_) = 0;               // slot the next point overwrites once full
  std::vector<engine::ModelProbability> model_probabilities_ GUARDED_BY(mutex_);
  std::optional<engine::PlatformAttitude> platform_ GUARDED_BY(mutex_);
  std::vector<TargetPoint> targets_ GUARDED_BY(mutex_);
  std::vector<DirectionPoint> directions_ GUARDED_BY(mutex_);  // a ring like ring_
  size_t next_direction_ GUARDED_BY(mutex_) = 0;
  std::vector<DirectionPoint> sources_ GUARDED_BY(mutex_);
  std::optional<PresencePoint> presence_ GUARDED_BY(mutex_);
  uint64_t present_frames_ GUARDED_BY(mutex_) = 0;
  uint64_t frames_ GUARDED_BY(mutex_) = 0;
  uint64_t initialised_frames_ GUARDED_BY(mutex_) = 0;
};

}  // namespace localizer::server
