// An audio tracking session: samples in, one Estimate per frame out. Opened with an
// AudioSessionConfig (session_config.h).
//
// Blocks of any length are appended to a per-channel ring; every hop_samples a frame of
// frame_samples (per channel) is cut and the TDOA front end measures it.
// Without a track (or from the configured region, if any), acquisition
// (engine/acquisition/acquisition.h) searches the plausible volume; when the presence test
// says a source is there, the tracker starts from every position the frame allows (a
// particle filter keeps them all as modes until the data and the dynamics decide; Kalman
// filters take the strongest).
// With a track, the tracker predicts to the frame's instant; the presence test runs about
// the predicted position: present, the tracker updates (a pair whose main peak is far from
// the prediction while another of its candidate peaks is near is measured there: multipath;
// on small arrays, a reference pair that the pairs without the reference contradict is read
// where they agree: pair_closure.h, AudioSessionConfig::pair_closure);
// absent, the volume is searched — a
// source heard elsewhere for 3 frames in a row restarts the track there; none heard, the
// track coasts (predicts, no update) and is dropped after source_timeout_s. A window of
// anchored normalised innovations far above its chi-square bound (pair_noise.h,
// divergence_monitor.h) restarts the track through acquisition.
// Each estimate says whether the frame held a source, reports the strongest hypothesis with
// a covariance covering all live ones, and flags the estimate ambiguous while several live:
// the tracker's own modes, a 4-sensor track's mirror that moves as a source can
// (mirror_watch.h), and a mode that outscored the track at the last audit (until an audit
// finds the track's own, or a restart).
// Every block is validated first (sequence increasing, channel count, length, finite
// values); a rejected block leaves the session exactly as it was.
// A moving array (config.array_in_body_frame) is moved, every frame, to where its platform's
// attitude (from the IMU samples given with AddImu) puts it; until the first IMU sample its
// frames are measured but not tracked (the array's pose is unknown).
// Direction sessions (config.localization direction, or auto with a planar or linear array, or
// positions from a volumetric array whose config states max_sources >= 2):
// the same framing and block checks, and each frame goes to a DirectionStage
// (direction_stage.h: SRP-PHAT peaks, a direction tracker); estimates list the sources.
// A pure function of its config (seed included) and the blocks (and IMU samples) it was given.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "engine/array/array_geometry.h"
#include "engine/core/block.h"
#include "engine/core/estimate.h"
#include "engine/core/imu.h"
#include "engine/doa/array_shape.h"
#include "engine/pipeline/session_config.h"

namespace localizer::engine {

// What a session opened with `config` reports: config.localization with auto resolved from
// the array's shape and the constraints stated (session_config.h). INVALID_ARGUMENT for an
// array with fewer than 2 distinct sensors, or positions from a planar or linear array
// without the constraints they need (naming what is missing: "a planar array needs
// source_side for position", ...).
StatusOr<Localization> ResolveLocalization(const AudioSessionConfig& config);
// Whether such a session's estimates list sources (Session::reports_sources); the same errors.
StatusOr<bool> ReportsSources(const AudioSessionConfig& config);

class Session {
 public:
  // INVALID_ARGUMENT naming the field when config.Validate() fails or a stage refuses its
  // options, or when the array cannot give what config.localization asks for (a position
  // from a planar or linear array; directions from a moving array); FAILED_PRECONDITION for
  // backend gpu without a usable GPU.
  static StatusOr<std::unique_ptr<Session>> Create(const AudioSessionConfig& config);
  ~Session();
  Session(const Session&) = delete;
  Session& operator=(const Session&) = delete;

  // Validates and consumes one block; appends one Estimate per completed frame to `out`.
  // On error nothing is consumed and `out` is unchanged.
  Status Process(const BlockView& block, std::vector<Estimate>* out);

  // The stream lost `samples_per_channel` samples before the next block (a gap in the
  // sequence numbers): buffered samples are dropped, the next frame starts after the gap,
  // and the tracker predicts across the missing time. INVALID_ARGUMENT if negative or
  // above 2^40.
  Status Skip(int64_t samples_per_channel);

  // Moving arrays (config.array_in_body_frame): IMU samples, in time order, on the session
  // clock (seconds from the first sample); send those of a block before the block. All are
  // validated first: INVALID_ARGUMENT (naming the sample and field) consumes none.
  // FAILED_PRECONDITION on a session whose array is fixed in the world.
  Status AddImu(const std::vector<ImuSample>& samples);
  // Moving arrays: the platform's body origin in the world from now on (finite).
  Status SetPlatformOrigin(const Vec3& origin_m);

  const AudioSessionConfig& config() const;
  const std::string& backend() const;  // "cpu" or "gpu": what BuildComponents chose
  // What the session reports: config.localization with auto resolved; and its array's shape.
  Localization localization() const { return localization_; }
  // Whether its estimates list sources (Estimate::sources: directions, and positions from a
  // planar or linear array, or from a volumetric one stating max_sources >= 2) rather than the
  // tracker's one position.
  bool reports_sources() const { return direction_ != nullptr; }
  const ArrayShapeInfo& shape() const { return shape_; }
  int sensor_count() const { return static_cast<int>(config().sensors_m.size()); }
  // Position sessions: the array in the world at the latest frame; nullptr for direction
  // sessions (they have no TDOA model).
  const ArrayGeometry* geometry() const;
  uint64_t frames_processed() const;

 private:
  struct Impl;
  struct DirectionImpl;
  Session(ArrayShapeInfo shape, Localization localization, std::unique_ptr<Impl> impl,
          std::unique_ptr<DirectionImpl> direction);
  ArrayShapeInfo shape_;
  Localization localization_;
  std::unique_ptr<Impl> impl_;                // position sessions
  std::unique_ptr<DirectionImpl> direction_;  // direction sessions
};

}  // namespace localizer::engine
