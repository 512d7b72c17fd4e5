// HandoffTracker's contract (engine/filters/handoff_tracker.h) on scripted trackers: restarts
// from several hypotheses go to the acquiring filter and from one Gaussian to the follower, the
// hand-off waits for kSteadyUpdates single-hypothesis updates in a
// row and starts the follower from the acquirer's state, a restart takes the track back (and
// suspends the follower), and a follower that cannot start leaves it where it is.
#include "engine/filters/handoff_tracker.h"

#include <gtest/gtest.h>

#include <memory>
#include <vector>

namespace localizer::engine {
namespace {

struct Script {
  int hypotheses = 1;
  bool refuse_initialise = false;
  int initialisations = 0;
  int updates = 0;
  int predicts = 0;
  int suspensions = 0;
  TrackState started_from;
};

class ScriptedTracker final : public Tracker {
 public:
  explicit ScriptedTracker(Script* script) : s_(script) {}
  bool initialised() const override { return true; }
  Status Initialise(const TrackState& belief) override {
    if (s_->refuse_initialise) return ResourceExhausted("no slot");
    ++s_->initialisations;
    s_->started_from = belief;
    state_ = belief;
    return Status::Ok();
  }
  std::vector<WeightedBelief> Hypotheses() const override {
    return std::vector<WeightedBelief>(static_cast<size_t>(s_->hypotheses),
                                       WeightedBelief{1.0 / s_->hypotheses, state_});
  }
  void Predict(double) override { ++s_->predicts; }
  void Suspend() override { ++s_->suspensions; }
  StatusOr<UpdateReport> Update(const Measurement&) override {
    ++s_->updates;
    state_.mean(0) += 1.0;  // something the follower must inherit
    return UpdateReport{};
  }
  TrackState State() const override { return state_; }

 private:
  Script* s_;
  TrackState state_;
};

TEST(HandoffTracker, HandsOverAfterSteadyUpdatesAndTakesTheTrackBackOnARestart) {
  Script acquire, follow;
  HandoffTracker tracker(std::make_unique<ScriptedTracker>(&acquire), std::make_unique<ScriptedTracker>(&follow));
  acquire.hypotheses = 2;
  ASSERT_TRUE(tracker.InitialiseMixture({{0.5, TrackState{}}, {0.5, TrackState{}}}).ok());
  EXPECT_EQ(acquire.initialisations, 1);
  const Measurement m;
  for (int i = 0; i < 5; ++i) ASSERT_TRUE(tracker.Update(m).ok());
  EXPECT_FALSE(tracker.following()) << "two hypotheses live: the acquirer keeps the track";
  acquire.hypotheses = 1;
  for (int i = 1; i < HandoffTracker::kSteadyUpdates; ++i) ASSERT_TRUE(tracker.Update(m).ok());
  EXPECT_FALSE(tracker.following());
  ASSERT_TRUE(tracker.Update(m).ok());
  ASSERT_TRUE(tracker.following());
  EXPECT_EQ(follow.initialisations, 1);
  EXPECT_EQ(follow.started_from.mean(0), 5.0 + HandoffTracker::kSteadyUpdates);  // the acquirer's state
  tracker.Predict(0.1);
  ASSERT_TRUE(tracker.Update(m).ok());
  EXPECT_EQ(follow.updates, 1);
  EXPECT_EQ(follow.predicts, 1);
  EXPECT_EQ(acquire.updates, 5 + HandoffTracker::kSteadyUpdates);
  EXPECT_EQ(tracker.State().mean(0), follow.started_from.mean(0) + 1.0);

  ASSERT_TRUE(tracker.InitialiseRegion(Vec3(-1, -1, -1), Vec3(1, 1, 1), 1.0).ok());
  EXPECT_FALSE(tracker.following()) << "a restart goes back to the acquirer";
  EXPECT_EQ(follow.suspensions, 1) << "and tells the follower it will not be stepped";
  ASSERT_TRUE(tracker.Update(m).ok());
  EXPECT_EQ(follow.updates, 1);
  ASSERT_TRUE(tracker.InitialiseMixture({{1.0, TrackState{}}}).ok());
  EXPECT_EQ(follow.suspensions, 1) << "a follower not following is not suspended again";
  EXPECT_TRUE(tracker.following()) << "one Gaussian goes to the follower at once";
  EXPECT_EQ(follow.initialisations, 2);
  EXPECT_EQ(acquire.suspensions, 0);
  ASSERT_TRUE(tracker.Update(m).ok());
  EXPECT_EQ(follow.updates, 2);
}

TEST(HandoffTracker, AFollowerThatCannotStartLeavesTheTrackWithTheAcquirer) {
  Script acquire, follow;
  follow.refuse_initialise = true;
  HandoffTracker tracker(std::make_unique<ScriptedTracker>(&acquire), std::make_unique<ScriptedTracker>(&follow));
  ASSERT_TRUE(tracker.Initialise(TrackState{}).ok());
  EXPECT_FALSE(tracker.following()) << "the follower refused its start";
  EXPECT_EQ(acquire.initialisations, 1);
  const Measurement m;
  for (int i = 0; i < 3 * HandoffTracker::kSteadyUpdates; ++i) ASSERT_TRUE(tracker.Update(m).ok());
  EXPECT_FALSE(tracker.following());
  EXPECT_EQ(acquire.updates, 3 * HandoffTracker::kSteadyUpdates);
  follow.refuse_initialise = false;
  ASSERT_TRUE(tracker.Update(m).ok());
  EXPECT_TRUE(tracker.following()) << "the next steady update tries again";
}

}  // namespace
}  // namespace localizer::engine
