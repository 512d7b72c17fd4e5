// Which of a session's direction tracks are a room's reflections of another track's source
// (echo_test.h), from evidence gathered over the frames in which both were heard.
//
// Per pair of tracks heard in the same frame (confirmed, a peak taken) it keeps:
//   - the echo test's rho at every lag, averaged (a running mean over the first 1 / averaging
//     frames, then an exponential average with that weight, so a verdict can change when the
//     room or the sources do): one frame's largest rho over the searched lags is 0.14-0.25 by
//     chance, while a reflection's stays at its lag frame after frame;
//   - the share of the two beams' power that is each one's (a reflection is weaker than its
//     source);
//   - the correlation of the two beams' frame-to-frame power changes (log power in four
//     sub-bands of the selective bins, consecutive frames, averaged with envelope_averaging):
//     a reflection's beam holds its source's signal, so its power rises and falls with the
//     source's; a second talker's beam holds the first talker's reflections too, at one lag
//     (rho 0.2-0.4 where its own talker is 5 dB weaker), but its power follows its own talker;
//   - whether each has been heard without the other for independent_run_frames frames in a
//     row (a reflection outlives its source by its extra path's delay, far less than a frame).
// Track j is track i's echo when the pair has min_frames frames of both, j's averaged beam
// power is below i's, j has not been heard on its own, the envelopes correlate by at least
// min_envelope_correlation and the averaged rho where j lags i reaches min_rho at some lag.
//
// Measured (ACCURACY.md, "Reflections heard as sources"): on the line's seeded rooms it takes
// a ceiling image's track (28 s of false source per minute) to nothing, but most of a line's
// false time is images merged with the direct peak, which it cannot separate: over seven draws
// false time falls by 0.2-2.4 s per minute and the heard share by 0.1-0.8 points. Hence an
// option (AudioSessionConfig::direction_echo_test), off by default.
//
// Cost: the echo test's, on the frames where at least two tracks are heard; nothing else.
// Not thread-safe; one per session.
#pragma once

#include <cstdint>
#include <map>
#include <utility>
#include <vector>

#include "engine/core/status.h"
#include "engine/core/types.h"
#include "engine/doa/array_shape.h"
#include "engine/doa/direction_tracker.h"
#include "engine/doa/echo_test.h"

namespace localizer::engine {

struct EchoWatchOptions {
  EchoTestOptions test;
  double averaging = 0.1;                  // in (0, 1]: rho's and the power share's weight per frame
  int min_frames = 8;                      // >= 1: frames of both (and of consecutive pairs of them) before a verdict
  double min_rho = 0.17;                   // in (0, 1)
  double min_envelope_correlation = 0.35;  // in [-1, 1]
  double envelope_averaging = 0.01;        // in (0, 1]
  int independent_run_frames = 5;          // >= 1

  Status Validate() const;
};

class EchoWatch {
 public:
  // INVALID_ARGUMENT naming the option (echo_test.h's included).
  static StatusOr<EchoWatch> Create(const std::vector<Vec3>& sensors_m, const ArrayShapeInfo& shape,
                                    const EchoWatchOptions& options);

  // The frame (sensors x frame_samples floats, channel-major) and the tracks the tracker
  // reports for it; heard[k]: tracks[k] took a peak this frame. Call for every frame (the
  // envelopes compare consecutive ones). Pairs of tracks no longer reported are forgotten.
  void Frame(const float* frame, const std::vector<SourceTrack>& tracks, const std::vector<char>& heard);
  // The track (SourceTrack::id) is, by the evidence so far, another reported track's echo.
  bool IsEcho(uint64_t id) const;

  // A pair's evidence that `later` is `earlier`'s echo, for reports and tests (false: none).
  struct PairView {
    int frames = 0;            // frames both were heard and told apart
    double best_rho = 0.0;     // the largest averaged rho where `later` lags
    int best_lag = 0;          // samples, where it lies
    double power_share = 0.0;  // averaged share of the two beams' power that is `later`'s
    double envelope_correlation = 0.0;
    bool later_independent = false;  // `later` was heard on its own
  };
  bool View(uint64_t earlier, uint64_t later, PairView* out) const;

 private:
  EchoWatch(EchoTest test, const ArrayShapeInfo& shape, const EchoWatchOptions& options)
      : test_(std::move(test)), shape_(shape), options_(options) {}
  Vec3 DirectionOf(const SourceTrack& track) const;  // a linear array's: any at the cone angle
  static constexpr int kBands = EchoEvidence::kSubBands;
  // Per pair, keyed by (lower id, higher id); "a" is the lower id's track, "b" the higher's.
  struct Pair {
    int frames = 0;
    std::vector<double> b_lags;  // averaged rho where b's beam lags a's
    std::vector<double> a_lags;  // ... and the other way
    double b_share = 0.0;        // averaged share of the beams' power that is b's
    int64_t last_frame = -2;     // the last frame both were heard (-2: none), and their sub-bands' log power
    double log_power_a[kBands] = {}, log_power_b[kBands] = {};
    int envelope_frames = 0;  // consecutive frames of both, and averaged products of the changes
    double change_a_sq = 0.0, change_b_sq = 0.0, change_product = 0.0;
    int a_run = 0, b_run = 0;  // frames in a row each has been heard without the other
    bool a_independent = false, b_independent = false;
    double EnvelopeCorrelation() const;
    void AddEnvelopes(const EchoEvidence& e, int64_t frame, double min_weight);
  };
  bool Echo(const Pair& p, bool b_is_later) const;
  EchoTest test_;
  ArrayShapeInfo shape_;
  EchoWatchOptions options_;
  std::map<std::pair<uint64_t, uint64_t>, Pair> pairs_;
  std::vector<uint64_t> echoes_;  // the ids judged echoes after the last frame
  int64_t frame_ = 0;             // frames seen
  EchoEvidence evidence_;         // scratch
};

}  // namespace localizer::engine
