#include "engine/filters/handoff_tracker.h"

namespace localizer::engine {

void HandoffTracker::Restarted() {
  if (following_) follow_->Suspend();
  following_ = false;
  single_updates_ = 0;
}

Status HandoffTracker::Initialise(const TrackState& belief) {
  Restarted();
  // One Gaussian is one hypothesis: straight to the follower, unless it cannot start.
  if (follow_->Initialise(belief).ok()) {
    following_ = true;
    return Status::Ok();
  }
  return acquire_->Initialise(belief);
}

Status HandoffTracker::InitialiseRegion(const Vec3& min_m, const Vec3& max_m, double speed_sigma_mps) {
  Restarted();
  return acquire_->InitialiseRegion(min_m, max_m, speed_sigma_mps);
}

Status HandoffTracker::InitialiseMixture(const std::vector<WeightedBelief>& components) {
  if (components.size() == 1) return Initialise(components.front().belief);
  Restarted();
  return acquire_->InitialiseMixture(components);
}

void HandoffTracker::SetBounds(const Vec3& min_m, const Vec3& max_m) {
  acquire_->SetBounds(min_m, max_m);
  follow_->SetBounds(min_m, max_m);
}

StatusOr<UpdateReport> HandoffTracker::Update(const Measurement& measurement) {
  if (following_) return follow_->Update(measurement);
  StatusOr<UpdateReport> report = acquire_->Update(measurement);
  if (!report.ok()) return report;
  single_updates_ = acquire_->Hypotheses().size() == 1 ? single_updates_ + 1 : 0;
  // A follower that cannot start (a full device bank, a device error) leaves the track here.
  if (single_updates_ >= kSteadyUpdates && follow_->Initialise(acquire_->State()).ok()) following_ = true;
  return report;
}

}  // namespace localizer::engine
