// The frame step of a session that follows sources by direction (AudioSessionConfig::
// localization resolved to direction, or to position with a planar or linear array, or with a
// volumetric one whose config states max_sources >= 2): each
// frame's SRP-PHAT peaks (engine/doa/srp_phat.h) go to a direction tracker
// (engine/doa/direction_tracker.h), and the estimate lists the sources it follows. With
// positions, each source heard in the frame also gets a near-field fit near its direction
// (engine/doa/near_field.h): SourceEstimate::position_m where the frame bounds its range.
// With several sources heard in a frame, each is fitted again on the spectrum with the others
// removed at the lags of their first fits (PairSpectra::RemoveDelay): on the whole spectrum a
// fit also sums the other sources' peaks.
//
// Per frame: up to config.max_sources peaks, each above the threshold set by
// config.presence_false_alarm per search; the tracker associates them with its tracks
// (identities kept through pauses of up to max_coast_s), confirms new ones after M of N
// frames and deletes silent ones. Estimate::sources gets the confirmed and coasting tracks;
// a track the tracker gave a peak this frame (status confirmed) is heard (source_present)
// and reports the power of the peak nearest to it; a coasting one is a prediction, present
// (with power_db NaN) only within config.direction_present_hold_s of a frame on which it took
// its frame's strongest peak after 4 hits in the last 5 frames: a talker between syllables.
// The SRP's pairs are weighted against a room's diffuse sound unless
// config.direction_diffuse_weighting is false (engine/doa/pair_spectra.h).
// Estimate::source_present says
// whether any peak passed the threshold; presence_statistic is the strongest peak's statistic (0 when none passed) and
// presence_threshold the threshold.
// With config.direction_echo_test, a track the echo watch calls another's reflection
// (engine/doa/echo_watch.h) is left out of Estimate::sources.
// With config.direction_present_drop_db, a track whose peak this frame lies that many dB below
// its own running level is not present (its source stopped; what it took is the room's).
// Cost: SrpPhat's (srp_phat.h: about 0.1 ms per frame for one source on a 4-microphone
// board) plus the tracker's, tens of microseconds for a few tracks; the echo watch's, about
// 45 us on frames where two or more tracks are heard on an 8-microphone line. Not thread-safe.
#pragma once

#include <complex>
#include <map>
#include <memory>
#include <optional>
#include <vector>

#include "engine/core/estimate.h"
#include "engine/core/status.h"
#include "engine/doa/array_shape.h"
#include "engine/doa/direction_tracker.h"
#include "engine/doa/echo_watch.h"
#include "engine/doa/near_field.h"
#include "engine/doa/srp_phat.h"
#include "engine/pipeline/session_config.h"

namespace localizer::engine {

// The near-field options a session's config states (source_side, source_plane, the
// sample rate and sound speed).
NearFieldOptions NearFieldOptionsFor(const AudioSessionConfig& config);

class DirectionStage {
 public:
  // INVALID_ARGUMENT naming the option (a source_side in a planar array's plane, positions
  // from a linear array without source_plane, ...).
  static StatusOr<std::unique_ptr<DirectionStage>> Create(const AudioSessionConfig& config, bool positions);

  const ArrayShapeInfo& shape() const { return srp_.shape(); }

  // One frame (sensors x frame_samples floats, channel-major) at instant t_s: fills e's
  // sources and presence fields.
  void Frame(const float* frame, double t_s, Estimate* e);

 private:
  DirectionStage(SrpPhat srp, DirectionTracker tracker, std::optional<NearFieldLocator> near,
                 std::optional<EchoWatch> echoes, double drop_db, double hold_s)
      : srp_(std::move(srp)),
        tracker_(std::move(tracker)),
        near_(std::move(near)),
        echoes_(std::move(echoes)),
        drop_db_(drop_db),
        hold_s_(hold_s) {}
  // Where a heard source's near-field fit looks (linear arrays: the cone angle's direction in
  // the plane).
  Vec3 FitDirection(const SourceEstimate& source) const;
  void Apply(const NearFieldFix& fix, SourceEstimate* source) const;
  // Near-field fits of the heard sources among e->sources[first...]: on the whole spectrum,
  // then, with two or more, RefitAmongOthers.
  void LocateHeard(Estimate* e, size_t first);
  // Each heard source fitted again with the others removed from the spectrum.
  void RefitAmongOthers();
  // AudioSessionConfig::direction_present_hold_s: coasting sources among e->sources[first...]
  // heard within hold_s_ are present.
  void Hold(double t_s, Estimate* e, size_t first);

  // A source without a fit is removed at the lags of a plane wave: a point this far along
  // its direction gives them to well under 1e-6 samples for any array that fits in a room.
  static constexpr double kPlaneWaveRange_m = 1e5;

  SrpPhat srp_;
  DirectionTracker tracker_;
  std::optional<NearFieldLocator> near_;  // sessions with positions
  std::optional<EchoWatch> echoes_;       // AudioSessionConfig::direction_echo_test
  std::vector<char> heard_tracks_;        // per track of tracks_: it took a peak this frame
  // AudioSessionConfig::direction_present_drop_db (0: off), and each reported track's running
  // level (its peaks' power_db, averaged with kLevelWeight per frame it is present, with
  // kHiddenLevelWeight per frame it is not).
  double drop_db_ = 0.0;
  std::map<uint64_t, double> track_level_db_;
  static constexpr double kLevelWeight = 0.05;
  static constexpr double kHiddenLevelWeight = 0.005;
  // AudioSessionConfig::direction_present_hold_s (0: off), and when each reported track was
  // last present.
  double hold_s_ = 0.0;
  struct Heard {
    double t_s = 0.0;
    bool holds = false;  // it led that frame, with kHoldHits hits in the last kHoldWindowFrames
  };
  std::map<uint64_t, Heard> last_heard_;
  static constexpr int kHoldHits = 4;
  static constexpr int kHoldWindowFrames = 5;
  std::vector<SourceTrack> tracks_;
  // Per frame scratch of LocateHeard (heard_[k]: the index in Estimate::sources).
  std::vector<size_t> heard_;
  std::vector<Vec3> directions_;
  std::vector<NearFieldFix> fixes_;
  std::vector<double> lags_;  // source k, pair p: lags_[k * pairs + p]
  Measurement residual_field_;
  std::vector<std::complex<double>> taken_;
};

}  // namespace localizer::engine
