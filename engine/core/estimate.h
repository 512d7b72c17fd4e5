// What a session returns for each frame.
#pragma once

#include <Eigen/Geometry>
#include <cstdint>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "engine/core/track_status.h"
#include "engine/core/types.h"

namespace localizer::engine {

struct StageTimings {
  double tdoa_s = 0.0;    // wall time of the TDOA front end for this frame
  double filter_s = 0.0;  // wall time of predict + update + estimate
};

// One motion hypothesis of a multiple-model tracker (IMM, multiple-model particle filter)
// and its posterior probability after this frame's update.
struct ModelProbability {
  std::string model;         // the hypothesis' name, e.g. "cv", "ct", "ct-left"
  double probability = 0.0;  // in [0, 1]; a tracker's list sums to 1
};

// Where a moving array's platform was at a frame's instant (engine/pipeline/platform_pose.h):
// body -> world attitude (East-North-Up world), its Euler angles z-y'-x'' and their std, and
// the body origin in the world.
struct PlatformAttitude {
  Eigen::Quaterniond body_to_world = Eigen::Quaterniond::Identity();
  Vec3 euler_rad = Vec3::Zero();  // (roll, pitch, yaw)
  Vec3 euler_sd_rad = Vec3::Zero();
  Vec3 origin_m = Vec3::Zero();
};

// One acoustic source followed by direction (sessions whose localization is direction:
// planar and linear arrays, or any array asked for directions; engine/pipeline/
// direction_stage.h). Angles in the array's frame: azimuth = atan2(y, x), elevation from the
// x-y plane towards +z; a linear array observes only the cone angle to its axis (the other
// fields NaN).

struct SourceEstimate {
  static constexpr double kNan = std::numeric_limits<double>::quiet_NaN();
  uint64_t source_id = 0;  // 1, 2, 3, ...: kept by a source through its pauses, never given to another (gaps possible)
  TrackStatus status = TrackStatus::kTentative;
  Vec3 direction = Vec3::Constant(kNan);  // unit, array -> source
  double azimuth_rad = kNan;
  double elevation_rad = kNan;
  double cone_angle_rad = kNan;  // linear arrays: angle to the array axis, [0, pi]
  double sigma_rad = kNan;       // RMS angular standard deviation of the estimate
  // This frame's peak assigned to the source: heard (present) and its power over the noise
  // level (dB; NaN when not heard: the direction is a prediction). A source that led its
  // recent frames stays present without a peak for AudioSessionConfig::
  // direction_present_hold_s (a pause between syllables), with power_db NaN.
  bool source_present = false;
  double power_db = kNan;
  // Positions from a planar or linear array (localization position; engine/doa/near_field.h):
  // where this frame's fit bounds the source's range (heard, and the range's standard
  // deviation within a third of the range), its position in the array's frame and the fit's
  // covariance (m^2; a linear array's in its source plane); NaN otherwise. range_sd_m: the
  // fit's range standard deviation from the array's centroid whenever a fit was made (also
  // far field), NaN when none was.
  Vec3 position_m = Vec3::Constant(kNan);
  Mat3 position_covariance_m2 = Mat3::Constant(kNan);
  double range_sd_m = kNan;
};

struct Estimate {
  uint64_t frame_index = 0;  // 0, 1, 2, ... within the session
  uint64_t sequence = 0;     // sequence number of the block that completed this frame
  // Reception instant at the reference sensor of the frame centre, seconds from the first
  // sample. The position is where the source was when it emitted the sound that reached
  // the reference sensor at t_s (emission time = t_s - range / c).
  double t_s = 0.0;
  bool initialised = false;    // false until the tracker has a first fix (state then zero)
  bool reinitialised = false;  // true on the frame the tracker was reset after divergence
  // Source presence (engine/acquisition/presence.h): whether this frame holds a source, and
  // the detection statistic behind the decision (the spatial spectrum's peak over its
  // noise-only spread; present when statistic >= threshold, the threshold set by the
  // session's per-frame false-alarm probability). Without a source the tracker predicts
  // but does not update; after AudioSessionConfig::source_timeout_s the track is dropped.
  bool source_present = false;
  double presence_statistic = 0.0;
  double presence_threshold = 0.0;
  // Several position hypotheses fit the data (e.g. the two exact TDOA solutions of a
  // 4-sensor array, or a position an audit's volume search found better than the track):
  // `state` is the strongest, `covariance` covers all of them (their spread about `state`
  // included), `modes` counts them. modes = 1 when resolved, 0 when not initialised.
  bool ambiguous = false;
  int modes = 0;
  // Range observability (position sessions): range_sd_m is the standard deviation of the
  // source's range from the array's centroid that this frame's TDOAs alone allow at the
  // estimate (the Cramer-Rao bound with each pair's own delay sigma; 0 when not computed).
  // far_field: range_sd_m exceeds a third of the range, so the frame's data do not bound
  // the range from above at three sigma (the TDOAs fix 1/range, nearly Gaussian, not
  // range): the direction from the centroid holds, the range is the tracker's guess. The
  // direction a volumetric array gives when its source is far (issue 18's `auto`).
  bool far_field = false;
  double range_sd_m = 0.0;
  Vec6 state = Vec6::Zero();  // (x, y, z, vx, vy, vz): m, m/s
  // Widened by the last frames' NIS over their pairs when above 1 (engine/pipeline/
  // innovation_consistency.h): the measurements' disagreement with the track is reported.
  Mat6 covariance = Mat6::Zero();
  double ess = 0.0;             // effective sample size after the update (particle filter)
  double tdoa_sigma_s = 0.0;    // TDOA noise std the tracker assumed (adaptive by default)
  int pairs_used = 0;           // pairs the tracker conditioned on (peak_snr high enough)
  double nis = 0.0;             // normalised innovation squared of this frame's TDOAs
  std::vector<double> delay_s;  // measured TDOA per pair, as in Measurement
  std::vector<double> quality;  // quality per pair
  // Multiple-model trackers (filter mmpf, imm): each hypothesis' probability after this
  // frame; empty for single-model filters and before initialisation.
  std::vector<ModelProbability> model_probabilities;
  // Sessions whose array rides a platform (AudioSessionConfig::array_in_body_frame): the pose the
  // frame's TDOA model used; unset for fixed arrays and before the first IMU sample.
  std::optional<PlatformAttitude> platform;
  // Direction sessions: the sources followed, in order of id (confirmed and coasting ones;
  // tentative ones are not reported). Position sessions leave it empty and fill the fields
  // above; direction sessions leave those at their defaults except the presence fields
  // (present: some source heard; the statistic is the strongest peak's).
  std::vector<SourceEstimate> sources;
  StageTimings timings;
};

}  // namespace localizer::engine
