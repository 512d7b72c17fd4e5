// Several acoustic sources followed by direction, with identities: each frame's SRP-PHAT
// peaks (srp_phat.h) become plots for the track-while-scan roles (engine/tws: a
// constant-velocity Kalman filter per track, chi-square gate, global nearest neighbour,
// M-of-N confirmation, deletion after misses).
//
// A direction is tracked as a point on the unit circle or sphere (the Cartesian plot
// interface, TwsTracker::ProcessCartesian):
//   volumetric  3-D: the peak's direction u, covariance sigma^2 (I - u u^T) +
//               (sigma / 10)^2 u u^T (tangential noise; the radius is nearly known);
//   planar      3-D: u, but the noise is sigma^2 in the plane's coordinates, where the lags
//               are linear, carried to the sphere: u = u_p + z n with z = sqrt(1 - |u_p|^2),
//               so a step d u_p moves u by (I - n u_p^T / z) d u_p. Along elevation the
//               sigma is sigma / sin(elevation): a board sees a source near its plane
//               through cos(elevation), which is flat there (in a room the peaks' elevation
//               scatters by 5-15 degrees from frame to frame while their azimuth holds to a
//               few). z is floored at sigma / max_elevation_sigma_rad. With the isotropic
//               covariance of the volumetric case, a peak's elevation jump fell outside its
//               track's gate and started a second track at the same azimuth;
//   linear      2-D: (cos theta, sin theta) of the cone angle theta, the same way.
// So "metres" in the tracker are radians on the sphere: velocity is an angular rate
// (rad/s), accel_noise an angular acceleration (rad/s^2). A track's reported direction is
// its position normalised. Planar arrays without a stated side: the direction on the
// normal's side (the mirror is the same source).
//
// Which peaks start tracks (precedence). A room's reflections are coherent copies of a
// source from other directions: they pass the noise threshold and repeat frame after frame
// while their source sounds, so a tracker that starts a track from every unexplained peak
// confirms them (issue 18: 270-500 s of false track per minute at RT60 0.2-0.6 s). A source
// that starts, though, is heard first through its direct path; its reflections follow,
// weaker, and build up over tens of milliseconds. So a tentative track starts only from the
// frame's peak whose direction rose most (DirectionPeak::rise: against the last frame that
// does not overlap this one), when that rise itself passes the detection threshold, on a
// frame whose power did not fall (onset.h; when a sound stops its direct path goes first
// and its reflections rise relative to it), and at most one per frame. For echo_window_s
// after any direction rose so (a new source, or a paused one resuming and taken by its
// track), a later riser starts a track only if its statistic is at least that source's: a
// second source, not its reflections, which rise as the room fills. And when no confirmed
// track has taken a peak for lost_source_after_s (a steady source whose track was lost: it
// rises nowhere), the frame's strongest peak may start one too: a reflection is never the
// strongest while its source sounds. Costs: a source that starts while a louder one's echo
// window is open, or in the same frame as another, waits for its next onset; a source that
// sounds without onsets (a steady hum) beside others that are tracked is started only once it
// leads its frames ("Persistent leaders"), and never while it is quieter than another.
//
// Resuming. A talker's track coasts through a pause with a gate that widens as its
// prediction's uncertainty grows (to ~0.5 rad after 1 s), while the other talker's
// reflections keep arriving from fixed directions: the coasting track took one and followed
// it (most of the false-track time left after precedence). A paused source that resumes is
// heard as a rise at its direction, like a new one; a reflection of a source that kept
// sounding is not. So a track silent for resume_after_s or more is updated only by a peak
// whose rise passes the threshold (TwsOptions::resume_misses,
// CartesianPlot::may_resume_track); it is taken after the tracks heard lately have taken
// theirs. Cost: a talker that resumes while another talks on often rises by less (its direct
// sound adds to a room the other's reverberation fills: 1.8-3.5 against a threshold of 4.3 in
// tests/bench/doa_room_report, seed 18 at RT60 0.4 s); its track is deleted after max_coast_s
// and, with the other talker heard, nothing starts on it again until a clear onset. Letting
// weaker rises (0.3 x the threshold) near where a track's source was heard resume it raised
// detection by up to 18 points but also kept tracks on reflections 15-25 degrees from a talker
// alive (more false and duplicate track time on unseen seeds): tried, not kept (ACCURACY.md).
//
// Identities. A paused talker's track does not always survive its pause: it coasts on its
// rate estimate (about 0.2-0.5 rad/s in a room, from the peaks' scatter), or it takes stray
// peaks it may still take before resume_after_s (reflections of the other talker, 10-20
// degrees from it at RT60 0.4-0.6 s), and is carried away. When the talker resumes its rising
// peak is outside that track's gate and starts a new track, while the old one lingers up to
// max_coast_s away from every source: in tests/bench/doa_room_report most of the false-track
// time left after the rules above, and most identity switches, were this. So each track keeps
// where its source was last heard (its anchor: its first plot, the latest rising peak it
// took, or its position after steady_hits hits in a row); a track confirmed within the
// tracker's gate of another's anchor (azimuths, for planar arrays) is that source resuming and
// takes its identity; of the tracks that share an identity only the one whose source was
// heard last is reported (the others stay in the tracker, and speak for it again if heard
// again). Cost: a new source starting within the gate (about 17 degrees with the default
// sigma) of where a track's source was heard, while that track lives, takes its identity.
// A talker silent for longer than max_coast_s loses its track; for remember_identity_s after
// that deletion its identity (with its anchor and its leading record) is remembered, and a
// track confirmed within the gate of that anchor takes it. Deleted tracks whose source was not
// being reported (leading, below) are not remembered. On tests/bench/doa_room_report seeds
// 1-30 this cut identity switches from 0 / 11 / 44 to 0 / 3 / 14 at RT60 0.2 / 0.4 / 0.6 s
// (19 / 62 / 113 to 7 / 29 / 49 with random azimuths), and on seeded rooms through the CLI the
// identities per talker from 2.57 to 1.59 (square), 2.12 to 1.41 (circle), 1.67 to 1.49
// (line), heard share and false time within 0.6 points and 0.4 s per minute (ACCURACY.md). Cost:
// a new source starting within the gate of where a source fell silent up to
// max_coast_s + remember_identity_s before takes that source's identity.
//
// Coasting. A track's angular rate is estimated from its peaks, and in a room most of it is
// their scatter (0.2-0.5 rad/s for talkers that do not move). A constant-velocity track that
// coasts through a pause extrapolates that rate: 6-14 degrees in half a second. In
// tests/bench/doa_room_report such drifts were most of the false-track time left after the
// rules above (tracks more than 20 degrees from every talker; at RT60 0.6 s on seed 1, 115 of
// 191 false frames were in runs that began while both talkers were silent), and a drifted
// track no longer covered its talker when it resumed. A talker that falls silent has far more
// likely stayed where it was than moved on at that rate, so a coasting track's rate decays by
// exp(-dt / coast_rate_decay_s) per missed frame (tws coast_velocity_decay_s): it comes to
// rest about rate x coast_rate_decay_s (and one frame) from where its source was last heard.
// Cost: a source that moves while unheard (two crossing sources whose peaks merge for a
// while) is not followed through the gap by extrapolation. In the crossing test
// (tests/doa/direction_tracker_test.cc; 4 identity switches and 137 false-track frames with
// no decay) 0.03 / 0.05 / 0.1 / 0.15 / 0.2 / 0.25 s gave 7 / 3 / 4 / 4 / 4 / 6 switches and
// 153 / 160 / 146 / 142 / 133 / 126 frames; 0.2 s is the value that worsened neither and
// took the room's seeds 1 and 2 to at most 0.9 s of false track per minute.
//
// Leading. A reflection is a delayed, weaker copy of its source: while the source sounds, the
// reflection's peak is beside the direct one and below it, and when the source stops both
// go. Some reflections still rise past the threshold and start tracks (the rules above let
// through one on a frame whose direct peak barely rose), and on a line array, where every
// image source maps to a cone angle of its own, floor, ceiling and wall images held tracks
// that took peaks in 50-60 % of frames (74 s of false track per minute on the one-talker
// line scene, scenes/rooms). Such tracks seldom take their frame's strongest peak: over
// their lives 1 in 100 to 1 in 60 frames heard (the odd frame where the direct peak scatters
// away), against most frames for a talker alone and about half for two talking at once. So
// a confirmed track is reported (and counts as a heard source for the lost-source rule) only
// while it has led its frame in at least max(min_lead_frames, min_lead_share x hits) of the
// frames it took a peak in; it stays in the tracker meanwhile and keeps taking its
// reflection's peaks, which then move no other track. A track that continues another's
// identity inherits that track's count. Cost: a talker always quieter than another that
// never pauses while it talks never leads, and is not reported; a new source is reported from
// its first lead (usually its onset, where it rose most). Measured (ACCURACY.md, "Tracks that
// never lead"): on seeded rooms the project was not tuned on, false track time per minute
// 1.7 -> 0.9 (square), 11.6 -> 1.9 (circle), 37 -> 10 (line), heard share -0.4, -1.8 and
// -6.8 points; a share of 0.2 cost a talker on the three-talker line half its frames.
//
// Co-leaders (co_lead_share, off by default). Two steady sources that start together and
// never pause have no onset apart, and only the stronger ever leads: the weaker is never
// started (a 0.5-m tetrahedron, two sources 0.9 m away, 16 kHz: one heard in each frame).
// With co_lead_share 0.5 a peak of at least half the strongest's statistic counts as a lead,
// and the second peak that holds that share 3 frames in a row at one direction may start a
// track. Measured (ACCURACY.md, "Large arrays"): two sources around that tetrahedron, 12
// seeded scenes each, source-frames heard within 10 degrees 1067 -> 1426 (free field, 0.6-2 m)
// and 1318 -> 1878 (6-9 m); but on the 4- and 7-microphone boards' room campaigns false
// track time went 1.4 -> 8.8 and 2.0 -> 11.4 s per minute (a board's reflections hold half
// the direct peak's statistic often enough), for 2-3 points of heard share. Hence off.
//
// Persistent leaders. The rules above start and resume tracks on rises, and a talker that
// resumes while another talks on often does not rise past the threshold (the room is full of
// the other's sound). Its track then coasts beside its peaks without taking them, is deleted
// after max_coast_s, and nothing starts on it again while the other talker is heard, though
// it may be the frame's strongest peak for seconds (measured on seeded rooms through the CLI,
// square board: in 19 % of the frames where a talker sounded alone its direction held the
// frame's strongest peak and no track took it). A reflection seldom leads even one frame
// while its source sounds ("Leading" below), and hardly ever several in a row at one
// direction. So when the frame's strongest peak has stayed within the same-source gate of
// the previous frame's strongest for persistent_leader_frames frames in a row (3), on a frame
// whose power did not fall, it may resume a silent track and, where no track lies within
// twice the gate (about 34 degrees, so that a talker's scattered peaks do not start a second
// track beside its own), start one. Measured (ACCURACY.md, "Persistent leaders"): heard share
// of talker-frames on seeded rooms, square 54.0 -> 57.6 % and 61.9 -> 64.8 % (two campaign
// seeds), circle +1.4 and +0.7 points, line +0.7 and +0.1; false time on the square 0.95 ->
// 1.38 and 0.73 -> 0.88 s per minute. Cost: at RT60 0.6 s more duplicate and false track time
// (a talker's reflection that leads three frames in a row starts a track).
//
// Defaults suit talkers around a board: sigma 0.05 rad (3 degrees, about a small board's
// frame-by-frame spread in a reverberant room), angular acceleration 2 rad/s^2, 3 of 5
// frames to confirm, deletion after max_coast_s of silence (1 s: pauses in speech keep their
// identity), and after the direction's variance exceeds (0.5 rad)^2.
// Not thread-safe; one per session. Deterministic.
#pragma once

#include <cstdint>
#include <map>
#include <memory>
#include <vector>

#include "engine/core/status.h"
#include "engine/core/types.h"
#include "engine/doa/array_shape.h"
#include "engine/doa/onset.h"
#include "engine/doa/srp_phat.h"
#include "engine/tws/track_report.h"
#include "engine/tws/tws_tracker.h"

namespace localizer::engine {

struct DirectionTrackerOptions {
  double peak_sigma_rad = 0.05;
  double angular_accel_noise_radps2 = 2.0;
  int confirm_hits = 3;
  int confirm_window = 5;
  double max_coast_s = 1.0;
  double frame_period_s = 0.016;  // hop / sample rate: turns max_coast_s into frames
  double initial_rate_sigma_radps = 1.0;
  double max_elevation_sigma_rad = 0.3;  // planar arrays: the largest elevation sigma a peak is given
  // Precedence (see the class comment). false: every peak no track took starts a track.
  bool start_at_onsets_only = true;
  double onset_min_rise_db = 0.0;  // OnsetOptions::min_rise_db: the frame's power did not fall
  double onset_memory_s = 0.05;    // OnsetOptions::memory_s
  double echo_window_s = 0.1;      // after a direction rose, births only from peaks as strong
  // When no confirmed track has been heard this long (0: never), the frame's strongest peak
  // may start a track as well (see "Which peaks start tracks").
  double lost_source_after_s = 0.25;
  // A track silent this long (0: off) is resumed only by a peak that rose past the threshold
  // (see "Resuming" above).
  double resume_after_s = 0.25;
  // A track confirmed where another track's source was last heard takes that track's identity
  // (see "Identities" above; false: every track keeps its own).
  bool continue_identities = true;
  // ... and so does one confirmed where a deleted track's source was last heard, for this long
  // after the deletion (s, >= 0; 0: off). See "Identities".
  double remember_identity_s = 3.0;
  // Hits in a row after which a track's position is where its source is heard (>= 1).
  int steady_hits = 5;
  // A coasting track's angular rate decays with this time constant (s, >= 0; 0: off, it
  // coasts at constant rate). See "Coasting" above for why, and why 0.2 s.
  double coast_rate_decay_s = 0.2;
  // A confirmed track is reported only while it has taken its frame's strongest peak in at
  // least max(min_lead_frames, min_lead_share x its hits) frames (0, 0: off). See "Leading".
  int min_lead_frames = 1;
  double min_lead_share = 0.1;
  // Co-leaders (0: off, only the frame's strongest peak leads; in [0, 1]): a peak whose
  // statistic is at least this share of the frame's strongest also counts as a lead for the
  // track that took it, and the frame's second peak, when it holds this share for
  // persistent_leader_frames frames in a row at one direction, may start and resume tracks
  // as a persistent leader does. See "Co-leaders".
  double co_lead_share = 0.0;
  // The frame's strongest peak, when the strongest peak of this many frames in a row has been
  // within the same-source gate of the one before (0: off), on a frame whose power did not
  // fall, may start a track (where no track lies within twice the gate) and resume a silent
  // one. See "Persistent leaders".
  int persistent_leader_frames = 3;

  Status Validate() const;
};

struct SourceTrack {
  static constexpr double kNan = DirectionPeak::kNan;
  uint64_t id = 0;  // 1, 2, 3, ... never reused for another source (see "Identities"); gaps possible
  tws::TrackStatus status = tws::TrackStatus::kTentative;
  Vec3 direction = Vec3::Constant(kNan);  // unit; NaN for linear arrays
  double azimuth_rad = kNan;
  double elevation_rad = kNan;
  double cone_angle_rad = kNan;  // linear arrays
  double sigma_rad = kNan;       // RMS angular standard deviation of the estimate
  // The frames it took a peak in, bit i for i frames ago (bit 0: this frame), and whether it
  // took this frame's strongest peak (led: see "Leading").
  uint32_t hit_bits = 0;
  bool led = false;
};

class DirectionTracker {
 public:
  // INVALID_ARGUMENT naming the option.
  // `shape` as SrpPhat::shape() gives it (planar arrays need its unit normal in `axis`).
  static StatusOr<DirectionTracker> Create(const ArrayShapeInfo& shape, const DirectionTrackerOptions& options);

  // One frame's peaks at time t_s (after the previous frame's), strongest first as
  // SrpPhat::Analyse gives them (the lost-source and leading rules read the first as the
  // frame's strongest), and its in-band power
  // (SrpPhat::band_power, for onsets). Fills `out` with the confirmed and coasting tracks
  // (tentative ones too when asked), in order of id. A tentative track shows its own id; once
  // confirmed it may show another's (continue_identities).
  Status Update(double t_s, const std::vector<DirectionPeak>& peaks, double band_power, std::vector<SourceTrack>* out,
                bool include_tentative = false);
  bool last_frame_onset() const { return onset_.onset(); }

 private:
  DirectionTracker(const ArrayShapeInfo& shape, const DirectionTrackerOptions& options,
                   std::unique_ptr<tws::TwsTracker> tracker, OnsetDetector onset)
      : shape_(shape), options_(options), tracker_(std::move(tracker)), onset_(std::move(onset)) {}
  Mat3 PeakCovariance(const Vec3& u) const;  // 3-D shapes, rad^2
  // The peak's point in the tracker: its direction, or (cos, sin) of its cone angle (linear).
  Vec3 UnitOf(const DirectionPeak& peak) const;
  // Squared angular distance of two directions over 2 peak_sigma_rad^2 (azimuths for planar
  // arrays): one source's when below the tracker's gate.
  double SameSourceD2(const Vec3& a, const Vec3& b) const;
  // After a scan (reports_ holds every track, tentative too): anchors, and identities
  // continued. `riser`: the frame's peak that rose past the threshold most, or null.
  void UpdateLineages(double t_s, const DirectionPeak* riser);
  ArrayShapeInfo shape_;
  DirectionTrackerOptions options_;
  std::unique_ptr<tws::TwsTracker> tracker_;
  OnsetDetector onset_;
  double echo_until_s_ = -1e300;
  double echo_statistic_ = 0.0;
  double unheard_s_ = 1e300;  // since a reported confirmed track last took a peak (none yet: forever)
  // A run of frames whose peak (the strongest, or the second while it holds co_lead_share of
  // the strongest's statistic) stayed within the same-source gate of the frame before's
  // ("Persistent leaders", "Co-leaders").
  struct PeakRun {
    Vec3 u = Vec3::Constant(DirectionPeak::kNan);
    int frames = 0;
  };
  // Extends *run with this frame's peak u (NaN: none); true once it has lasted
  // persistent_leader_frames frames.
  bool Persists(PeakRun* run, const Vec3& u) const;
  // No track of the last frame (tentative too) within twice the same-source gate of u.
  bool NoTrackNear(const Vec3& u) const;
  PeakRun leader_;
  PeakRun second_;
  // Per track of the tws tracker (by its id).
  struct Lineage {
    uint64_t reported_id = 0;  // the identity it reports: its own, or the one it continues
    bool confirmed = false;    // has been confirmed
    bool shown = true;         // it speaks for its identity (of those that share it, the one heard last)
    int run = 0;               // hits in a row
    int hits = 0;              // frames in which it took a peak
    int leads = 0;             // of those, frames in which it took the frame's strongest peak
    uint32_t hit_bits = 0;     // SourceTrack::hit_bits
    bool led = false;          // it took this frame's strongest peak
    // Where its source was last heard: its first plot, the latest rising peak it took, or
    // its position after steady_hits hits in a row. NaN before the first.
    Vec3 anchor = Vec3::Constant(DirectionPeak::kNan);
    double anchor_s = -1e300;  // when it was set
  };
  // It has led its frame often enough to be reported ("Leading"): leads >=
  // max(min_lead_frames, min_lead_share x hits).
  bool Leads(const Lineage& l) const;
  std::map<uint64_t, Lineage> lineage_;
  std::vector<tws::CartesianPlot> plots_;
  std::vector<double> plot_share_;  // per plot: its peak's statistic over the frame's strongest
  std::vector<uint64_t> leaders_;   // UpdateLineages' scratch: per plot, the track that led on it
  std::vector<double> leader_d2_;
  struct Departed {  // a deleted track's lineage, remembered until until_s (remember_identity_s)
    Lineage lineage;
    double until_s;
  };
  std::vector<Departed> departed_;
  std::vector<tws::TrackReport> reports_;
};

}  // namespace localizer::engine
