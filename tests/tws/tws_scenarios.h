// Shared by the tws tests: run a simulated radar scenario through a tracker and score it.
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <vector>

#include "engine/sim/radar_scan.h"
#include "engine/tws/ospa.h"
#include "engine/tws/track_scoring.h"
#include "engine/tws/tws_tracker.h"

namespace localizer::engine::tws {

struct ScenarioScore {
  std::vector<double> ospa_m;       // per scan, confirmed tracks vs truth
  std::vector<int> confirmed;       // confirmed + coasting tracks per scan
  std::vector<int> truths_covered;  // truths with a confirmed track within `near_m`, per scan
  int identity_switches = 0;
  double purity = 1.0;
  int max_tracks = 0;
  uint64_t max_id = 0;
};

inline ScenarioScore RunScenario(const RadarScanSimulator& sim, TwsTracker& tracker, int scans, double ospa_cutoff_m,
                                 double near_m) {
  ScenarioScore score;
  TrackScoring scoring(near_m);
  std::vector<TrackReport> tracks;
  for (int k = 0; k < scans; ++k) {
    const RadarScanFrame frame = sim.Frame(k);
    const Status st = tracker.Process(frame.scan);
    EXPECT_TRUE(st.ok()) << st.ToString();
    tracker.Tracks(&tracks, /*include_tentative=*/false);
    std::vector<Eigen::Vector3d> truth_p, track_p;
    std::vector<Labelled> truth_l, track_l;
    for (const TargetTruth& t : frame.truth) {
      truth_p.push_back(t.position_m);
      truth_l.push_back({t.id, t.position_m});
    }
    for (const TrackReport& r : tracks) {
      track_p.push_back(r.position_m);
      track_l.push_back({r.id, r.position_m});
      score.max_id = std::max(score.max_id, r.id);
    }
    score.ospa_m.push_back(Ospa(truth_p, track_p, ospa_cutoff_m, 2.0));
    score.confirmed.push_back(static_cast<int>(tracks.size()));
    int covered = 0;
    for (const auto& t : truth_p) {
      for (const auto& p : track_p) {
        if ((t - p).norm() < near_m) {
          ++covered;
          break;
        }
      }
    }
    score.truths_covered.push_back(covered);
    scoring.Add(truth_l, track_l);
    score.max_tracks = std::max(score.max_tracks, tracker.track_count());
  }
  score.identity_switches = scoring.identity_switches();
  score.purity = scoring.Purity();
  return score;
}

}  // namespace localizer::engine::tws
