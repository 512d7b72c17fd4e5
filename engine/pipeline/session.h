// A tracking session: samples in, one Estimate per frame out.
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
// the prediction while another of its candidate peaks is near is measured there: multipath);
// absent, the volume is searched — a
// source heard elsewhere for 3 frames in a row restarts the track there; none heard, the
// track coasts (predicts, no update) and is dropped after source_timeout_s. A window of
// anchored normalised innovations far above its chi-square bound (pair_noise.h,
// divergence_monitor.h) restarts the track through acquisition.
// Each estimate says whether the frame held a source, reports the strongest hypothesis with
// a covariance covering all live ones, and flags the estimate ambiguous while several live.
// Every block is validated first (sequence increasing, channel count, length, finite
// values); a rejected block leaves the session exactly as it was.
// A moving array (config.array_in_body_frame) is moved, every frame, to where its platform's
// attitude (from the IMU samples given with AddImu) puts it; until the first IMU sample its
// frames are measured but not tracked (the array's pose is unknown).
// A pure function of its config (seed included) and the blocks (and IMU samples) it was given.
#pragma once

#include <cstdint>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "engine/array/array_geometry.h"
#include "engine/attitude/attitude_filter.h"
#include "engine/core/imu.h"
#include "engine/core/block.h"
#include "engine/core/estimate.h"
#include "engine/filters/particle_filter.h"
#include "engine/tdoa/gcc_phat.h"
#include "engine/tws/tws_options.h"

namespace localizer::engine {

struct SessionConfig {
  // Array
  std::vector<Vec3> sensors_m;        // >= 4, not coplanar
  double sound_speed_mps = 1500.0;    // > 0 (1500 water, 343 air)
  int reference_sensor = 0;
  double sample_rate_hz = 0.0;        // > 0
  // Framing
  int frame_samples = 4096;           // per channel, in [64, 1 << 20]
  int hop_samples = 2048;             // in [1, frame_samples]
  int64_t max_block_samples = 1 << 22;  // per channel per block
  // TDOA front end
  Weighting weighting = Weighting::kPhat;
  double phat_beta = 0.8;
  double band_low_hz = 0.0;
  double band_high_hz = 0.0;          // 0: Nyquist
  // Impulsive-noise front end (engine/tdoa/despike.h): each frame's channels are clipped at
  // despike_k robust standard deviations before the GCC (0: off), keeping outliers that every
  // channel shows within the array's largest delay (a coherent impulsive source).
  double despike_k = 5.0;
  // Tracker
  // "pf" particle filter (particle_filter.h), "ekf" | "ukf" (kalman_filter.h), "mmpf"
  // multiple-model particle filter (multi_model_pf.h: cv, cv-manoeuvre, ct-left, ct-right
  // at 0.1 rad/s), "imm" interacting multiple model (imm_filter.h)
  std::string filter_type = "pf";
  std::string motion_model = "cv";    // ekf/ukf: "cv" | "ca" | "ct" | "singer"; others: "cv"
  ParticleFilterOptions filter;       // filter.seed is overwritten by `seed`; the Kalman
                                      // filters and the IMM read accel_noise_mps2 (their
                                      // motion noise), tdoa_sigma_s and min_peak_snr from it;
                                      // mmpf reads all of it (accel_noise_mps2: the base of
                                      // its hypotheses' noise)
  std::string imm_modes = "cv,ct";    // imm: its modes' motion models, comma-separated, unique
  std::string imm_variant = "ekf";    // imm: mode filters "ekf" | "ukf"
  std::string robust = "none";        // ekf/ukf/imm update: "none" | "huber" | "student-t"
                                      // (reweighted pairs, kalman_filter.h)
  // Former single-fix initialisation; kept for the wire contract, unused since acquisition
  // (engine/acquisition) initialises from every mode the data allows.
  double min_pair_quality = 1.5;
  double max_fix_std_m = 0.0;
  double init_speed_sigma_mps = 2.0;  // velocity spread at initialisation
  // A region known to hold the source: when min <= max (all finite), the tracker starts
  // from it at the first frame instead of waiting for a good fix. Unset by default.
  Vec3 init_region_min_m = Vec3::Constant(std::numeric_limits<double>::quiet_NaN());
  Vec3 init_region_max_m = Vec3::Constant(std::numeric_limits<double>::quiet_NaN());
  int divergence_window = 8;          // frames averaged by the divergence test
  // Physical bounds on the source position: a box whose sides may be infinite (unbounded;
  // the default on every side). Particles, fixes and acquisition candidates outside it are
  // impossible. A water column: bounds_max_m.z() = the surface, bounds_min_m.z() = the bottom.
  Vec3 bounds_min_m = Vec3::Constant(-std::numeric_limits<double>::infinity());
  Vec3 bounds_max_m = Vec3::Constant(std::numeric_limits<double>::infinity());
  // Acquisition (engine/acquisition): the volume searched for a source when there is no
  // trustworthy track, a sphere of this radius about the array centre intersected with the
  // bounds (0: 10 apertures).
  double search_radius_m = 0.0;
  // Source presence: the per-frame false-alarm probability the presence test is set for,
  // in (0, 0.1]; and how long a track coasts with no source heard before it is dropped and
  // acquisition restarts (> 0).
  double presence_false_alarm = 1e-3;
  double source_timeout_s = 2.0;
  // Moving array (platform_pose.h): sensors_m are in the platform's body frame (the IMU's
  // axes) and the session is fed IMU samples (AddImu); each frame's TDOA model uses the
  // sensors rotated by the platform's attitude at that frame and moved to its origin.
  // Estimates carry the platform pose. The particle filter then runs on the CPU.
  bool array_in_body_frame = false;
  AttitudeFilterOptions attitude;     // the platform's attitude filter
  Vec3 platform_origin_m = Vec3::Zero();  // body origin in the world until SetPlatformOrigin
  // Detection session (scan_session.h): the session takes scans of plots from a detecting
  // sensor instead of samples, and tracks many targets (track-while-scan). Only `tws`,
  // `label`-like fields and max_block_samples matter then; the array, framing, GCC and
  // single-target tracker fields are ignored and not validated.
  bool detections = false;
  tws::TwsOptions tws;
  std::string backend = "cpu";        // "cpu" | "gpu" | "auto"
  uint64_t seed = 1;

  Status Validate() const;  // INVALID_ARGUMENT naming the field
  // The TDOA front end's options: framing, weighting, band; the GCC is kept when the
  // tracker's likelihood reads it.
  GccOptions GccOptionsFor() const;
};

class Session {
 public:
  static StatusOr<std::unique_ptr<Session>> Create(const SessionConfig& config);
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

  const SessionConfig& config() const;
  const std::string& backend() const;  // "cpu" or "gpu": what BuildComponents chose
  const ArrayGeometry& array() const;
  uint64_t frames_processed() const;

 private:
  struct Impl;
  explicit Session(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace localizer::engine
