// The deleter alone (deleter.h): each rule at its edge, the M-of-N reachability against
// brute force over every continuation of random histories, and a coasting track deleted on
// the scan its predicted position variance (updater.h) crosses the bound.
#include "engine/tws/deleter.h"

#include <gtest/gtest.h>

#include <random>
#include <string>

#include "engine/tws/updater.h"

namespace localizer::engine::tws {
namespace {

TrackHistory After(const std::string& pattern) {  // "1" hit, "0" miss; the first is the initiating hit
  TrackHistory h;
  h.bits = 1u;
  h.age = h.hits = 1;
  for (size_t k = 1; k < pattern.size(); ++k) h.Record(pattern[k] == '1');
  return h;
}

TEST(Deleter, ATentativeTrackGoesWhenMOfNIsOutOfReach) {
  const Deleter deleter({3, 5, 5, 2000.0});
  EXPECT_EQ(deleter.Judge(After("100"), 0.0), Deletion::kKeep);            // 1 + 2 scans left = 3
  EXPECT_EQ(deleter.Judge(After("1000"), 0.0), Deletion::kUnconfirmable);  // 1 + 1 < 3
  EXPECT_EQ(deleter.Judge(After("1100"), 0.0), Deletion::kKeep);           // 2 + 1 = 3
  EXPECT_EQ(deleter.Judge(After("11000"), 0.0), Deletion::kUnconfirmable);
  EXPECT_EQ(std::string(DeletionName(Deletion::kUnconfirmable)), "unconfirmable");
}

TEST(Deleter, UnconfirmableExactlyWhenNoContinuationReachesM) {
  // Brute force: the rule gives a tentative track its first N scans to collect M hits; it
  // can still make it exactly when hits on every scan left before its N-th would do. (A
  // track not confirmed by its N-th scan is deleted even if a later window could fill.)
  std::mt19937_64 engine(3);
  std::bernoulli_distribution hit(0.4);
  for (int m = 1; m <= 4; ++m) {
    for (int n = m; n <= 6; ++n) {
      const Deleter deleter({m, n, 5, 2000.0});
      const MofN rule(m, n);
      for (int trial = 0; trial < 40; ++trial) {
        std::string pattern = "1";
        for (int k = 1; k < n + 2; ++k) {
          pattern += hit(engine) ? '1' : '0';
          TrackHistory h = After(pattern);
          if (rule.Reached(h)) break;  // the initiator would confirm it: not tentative
          // Best continuation: hits on every scan left until age N.
          TrackHistory best = h;
          while (best.age < n) best.Record(true);
          const bool reachable = rule.Reached(best);
          EXPECT_EQ(deleter.Judge(h, 0.0) == Deletion::kUnconfirmable, !reachable) << pattern << " " << m << "/" << n;
        }
      }
    }
  }
}

TEST(Deleter, AConfirmedTrackGoesAfterMaxCoastMissesInARow) {
  const Deleter deleter({3, 5, 4, 2000.0});
  TrackHistory h = After("111");
  h.confirmed = true;
  for (int miss = 1; miss <= 4; ++miss) {
    h.Record(false);
    EXPECT_EQ(deleter.Judge(h, 0.0), miss < 4 ? Deletion::kKeep : Deletion::kCoasted) << miss;
  }
  h.Record(true);  // a hit resets the count
  EXPECT_EQ(deleter.Judge(h, 0.0), Deletion::kKeep);
}

TEST(Deleter, AnyTrackGoesWhenItsPositionVarianceExceedsTheBound) {
  const Deleter deleter({1, 1, 1000, 100.0});
  TrackHistory h = After("1");
  h.confirmed = true;
  EXPECT_EQ(deleter.Judge(h, 100.0 * 100.0), Deletion::kKeep);
  EXPECT_EQ(deleter.Judge(h, 100.0 * 100.0 * (1.0 + 1e-12)), Deletion::kDiverged);
  // A coasting track: deleted on the scan its predicted variance crosses the bound, which
  // follows from the closed form of its growth (updater_test.cc).
  const double t = 1.0, sigma_a = 5.0;
  const KalmanUpdater<2> updater({sigma_a, FilterForm::kKalman, 1e-3});
  Eigen::Matrix4d p0 = Eigen::Matrix4d::Zero();
  p0.diagonal() << 100.0, 100.0, 25.0, 25.0;  // 10 m, 5 m/s
  FilterState<2> f = KalmanUpdater<2>::Start(Cv<2>::State::Zero(), p0);
  int want = 0;
  for (int n = 1; want == 0; ++n) {
    const double var = 100.0 + n * n * t * t * 25.0 + sigma_a * sigma_a * n * (4.0 * n * n - 1) / 12.0;
    if (var > 100.0 * 100.0) want = n;
  }
  int deleted_at = 0;
  for (int n = 1; n <= 100 && deleted_at == 0; ++n) {
    updater.Predict(f, t);
    KalmanUpdater<2>::Miss(f);
    h.Record(false);
    if (deleter.Judge(h, KalmanUpdater<2>::LargestPositionVariance(f)) == Deletion::kDiverged) deleted_at = n;
  }
  EXPECT_EQ(deleted_at, want);
}

}  // namespace
}  // namespace localizer::engine::tws
