// The session's state and its frame steps, shared by session.cc (framing, blocks, IMU,
// Create) and session_tracking.cc (acquisition, presence, audits, updates, reporting).
// Internal to engine/pipeline.
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <vector>

#include "engine/acquisition/acquisition.h"
#include "engine/acquisition/pair_closure.h"
#include "engine/filters/divergence_monitor.h"
#include "engine/pipeline/backend.h"
#include "engine/pipeline/framer.h"
#include "engine/pipeline/innovation_consistency.h"
#include "engine/pipeline/mirror_watch.h"
#include "engine/pipeline/platform_pose.h"
#include "engine/pipeline/range_observability.h"
#include "engine/pipeline/session.h"
#include "engine/tdoa/despike.h"
#include "engine/tdoa/pair_fusion.h"

namespace localizer::engine {

struct Session::Impl {
  Impl(AudioSessionConfig c, ArrayGeometry a, SessionComponents parts, std::unique_ptr<PlatformPose> pose,
       Acquisition acq)
      : config(std::move(c)),
        body_array(a),
        array(std::move(a)),
        platform(std::move(pose)),
        components(std::move(parts)),
        acquisition(std::move(acq)),
        framer(array.sensor_count(), config.frame_samples, config.hop_samples),
        monitor(config.divergence_window),
        mirror(config.tracker.particle.accel_noise_mps2),
        measured_mirror(config.tracker.particle.accel_noise_mps2) {
    despike.despike_k = config.despike_k;
    // A coherent impulse reaches every sensor within the aperture's travel time.
    despike.coincidence_samples =
        static_cast<int>(std::ceil(array.aperture_m() / config.sound_speed_mps * config.sample_rate_hz)) + 5;
  }

  void ProcessFrame(const float* frame, int64_t first_sample, uint64_t sequence, std::vector<Estimate>* out);
  // Starts the tracker from acquisition's modes (every one the data allows); false if none.
  bool StartFromModes(const std::vector<PositionMode>& modes);
  // The track's frame: predict, test presence near it, update or coast, watch for
  // divergence and for a source heard elsewhere; drops the track after source_timeout_s of
  // silence. Fills e's presence and filter fields.
  void TrackFrame(double dt_s, bool measured, Estimate* e);
  // No track: search the volume; a present source starts one.
  void AcquireFrame(bool measured, Estimate* e);
  // Acquisition's volume search of this frame, over every pair the front end measures: the
  // pairs without the reference are measured first, once per frame (small arrays only,
  // AudioSessionConfig::cross_pairs_max_sensors), so only frames that search pay for them.
  AcquisitionResult SearchAllPairs();
  // A present frame that the track explains much worse than each pair's best peak allows
  // (PresenceResult::unconstrained), or whose update used fewer than 3 pairs, is audited by
  // a volume search (at most every
  // kAuditSpacingFrames): no mode near the track scoring within the margin of the best, in
  // kOutscoredAudits audits in a row, restarts the track from the modes and the track
  // itself. Catches a track that locked on a wrong position while every test near it passes.
  // A frame where one channel has an earlier arrival at the track (Acquisition::EarlierArrival:
  // the track may sit on that channel's louder echo) is audited too, every kAuditSpacingFrames:
  // a mode that is one side of such a pair (its earlier arrival, or the echo whose earlier
  // arrival it is) counts as the track's own, and the other side is the contender (covered,
  // never a restart: no single frame tells them apart).
  void Audit(const TrackState& predicted, const PresenceResult& near, Estimate* e);
  // One channel has an earlier arrival at the track's predicted position, on a field with the
  // pairs without the reference (measured here once per frame).
  bool EchoedChannelAtTrack(const TrackState& predicted);
  // After an updated frame: follows the track's mirror (4-sensor arrays, mirror_watch.h).
  void WatchMirror(double t_s, double fallback_sigma_s, int pairs_used);
  // Conditions the tracker on this frame, fills e's filter fields, and restarts the tracker
  // through acquisition when the divergence test fires: from the frame's modes and the
  // track's own prediction (`predicted`), equally weighted.
  void UpdateAndWatch(const TrackState& predicted, Estimate* e);
  // The estimate's state: the strongest hypothesis, with a covariance that covers all of
  // them, a live mirror and an audit's contender; and whether this frame's TDOAs bound its
  // range (range_observability.h).
  void Report(Estimate* e);
  // Multipath: a pair whose main peak is far from where the track predicts it, while its GCC
  // has another peak (a local maximum at least kCandidateShare of the main peak's height)
  // within kAssociationGate predicted sigmas, is measured at that peak instead (the tallest
  // in the gate; returns how many pairs were changed), its sigma that peak's own (its
  // curvature at its own SNR, pair_noise.h OwnPeakSigmaS): a smaller peak is a less precise one.
  // Only while the tracker holds one hypothesis (`hypotheses`, the tracker's count): the
  // measurement is shared by all of them.
  int AssociateCandidates(const TrackState& predicted, size_t hypotheses);
  // Small arrays (AudioSessionConfig::pair_closure, cross_pairs_max_sensors): measures the
  // pairs without the reference and moves a reference pair they contradict (pair_closure.h).
  void CheckClosure();
  // Arrays that measure the pairs without the reference (AudioSessionConfig::pair_fusion): the
  // reference pairs' delays from every pair's peak (pair_fusion.h), each cross pair moved to
  // its reference pairs' instants by the rates `predicted` gives.
  void FusePairs(const TrackState& predicted);
  // The frame's pairs without the reference, measured at most once per frame (the front end
  // clears them with each Estimate; arrays it measures none for keep none).
  void MeasureCrossPairsOnce();

  // Before the frame centred at t_s: the delay rates the last reported track predicts for
  // its pairs, handed to the front end when some pair's peak would move by a sample or more
  // over the frame, else none (AudioSessionConfig::delay_rate_compensation).
  // Only for a fixed array and a tracker holding one hypothesis.
  void PredictDelayRates(double t_s);

  // Moving arrays: moves `array` and the tracker to the platform's pose at t_s; false
  // when there is no pose yet (no IMU sample).
  bool MoveArray(double t_s, Estimate* e);

  AudioSessionConfig config;
  ArrayGeometry body_array;                // as configured (the body frame, for a moving array)
  ArrayGeometry array;                     // in the world at the current frame
  std::unique_ptr<PlatformPose> platform;  // moving arrays only
  SessionComponents components;
  Acquisition acquisition;
  bool live = false;           // the tracker holds a track (not dropped)
  int frames_since_audit = 0;  // see Audit
  int outscored = 0;           // audits in a row that found the frame better explained elsewhere
  // The best mode of the last audit that found the track outscored (cleared by an audit that
  // finds the track's own, by a restart, and after kContenderFrames reports): Report covers
  // it, as it covers a live mirror, and says the estimate is ambiguous.
  std::optional<PositionMode> contender;
  int contender_frames = 0;
  double silent_s = 0.0;    // time since the source was last heard near the track
  int heard_elsewhere = 0;  // consecutive frames with the source present away from the track
  Framer framer;
  DespikeOptions despike;
  DespikeScratch despike_scratch;
  std::vector<float> despiked;  // a frame with samples clipped (DespikedFrame), when despiking
  DivergenceMonitor monitor;
  PairSigmaHistory pair_sigmas;       // the recent frames' delay sigmas, for Estimate::far_field
  InnovationConsistency consistency;  // the recent frames' NIS, for Estimate::covariance
  // 4-sensor arrays: the track's other exact solution, as the other root of the TDOAs the
  // track predicts (mirror) and of the frame's measured TDOAs (measured_mirror). Each misses
  // cases the other covers: near the branch point the track's own error moves its root by
  // metres (campaign scene 33000075), while pairs on echoes or a fast source make the measured
  // root jump (27000182). Report covers whichever is live.
  MirrorWatch mirror;
  MirrorWatch measured_mirror;
  PairClosure closure;               // small arrays: reference pairs checked by the cross pairs
  PairFusion fusion;                 // the reference pairs' delays from every pair
  std::vector<double> fusion_rates;  // per pair, s/s (empty: none)
  Measurement measurement;
  Eigen::VectorXd delays;
  std::optional<Vec6> single_track_mean;  // the last Report's track, when the tracker held one hypothesis
  std::vector<double> delay_rates;        // per pair, handed to the front end (empty: none)
  bool have_sequence = false;
  uint64_t last_sequence = 0;
  uint64_t frames = 0;
  double last_t_s = 0.0;
};

}  // namespace localizer::engine
