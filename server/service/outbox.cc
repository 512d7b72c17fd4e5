#include "server/service/outbox.h"

#include <algorithm>
#include <utility>

namespace localizer::server {

void EstimatePool::Put(ResponsePtr response) {
  // use_count is exact here: every other holder of an outbox's response is the outbox itself
  // (a replay queues its history again) or its caller under the same host lock.
  if (response == nullptr || response.use_count() != 1 || !response->has_estimate()) return;
  MutexLock lock(&mutex_);
  if (spare_.size() < kCapacity) spare_.push_back(std::const_pointer_cast<v1::TrackResponse>(std::move(response)));
}

std::shared_ptr<v1::TrackResponse> EstimatePool::TakeEstimate() {
  std::shared_ptr<v1::TrackResponse> response;
  {
    MutexLock lock(&mutex_);
    if (!spare_.empty()) {
      response = std::move(spare_.back());
      spare_.pop_back();
    }
  }
  if (response == nullptr) {
    response = std::make_shared<v1::TrackResponse>();
    response->mutable_estimate();
  } else {
    response->mutable_estimate()->Clear();  // the kind stays `estimate`; its storage stays
  }
  return response;
}

size_t EstimatePool::size() const {
  MutexLock lock(&mutex_);
  return spare_.size();
}

Outbox::Outbox(size_t history_capacity, EstimatePool* pool) : history_capacity_(history_capacity), pool_(pool) {}

void Outbox::Push(ResponsePtr response) {
  if (response->has_estimate() || response->has_tracks()) ++frames_;
  waiting_.push_back(std::move(response));
}

ResponsePtr Outbox::TakeNext() {
  if (in_flight_ || waiting_.empty()) return nullptr;
  in_flight_ = std::move(waiting_.front());
  waiting_.pop_front();
  return in_flight_;
}

void Outbox::Written() {
  if (!in_flight_) return;
  if (in_flight_->has_estimate()) {
    history_.push_back(std::move(in_flight_));
    if (history_.size() > history_capacity_) {
      if (pool_ != nullptr) pool_->Put(std::move(history_.front()));
      history_.pop_front();
    }
  }
  in_flight_.reset();
}

void Outbox::Failed() {
  if (!in_flight_) return;
  if (!in_flight_->has_opened()) waiting_.push_front(std::move(in_flight_));  // a resume sends a fresh one
  in_flight_.reset();
}

void Outbox::Reattach(ResponsePtr opened, const ResumePoint& resume) {
  // Its write in flight may never have reached the client: it goes first again (the replay
  // below drops it if the client says it has it).
  Failed();
  if (resume.received_none) {
    // The client has nothing: replay every written estimate still held, oldest first.
    for (auto it = history_.rbegin(); it != history_.rend(); ++it) waiting_.push_front(*it);
  } else if (resume.last_frame_received) {
    // Drop what the client has; replay written estimates it has not seen, oldest first.
    const uint64_t seen = *resume.last_frame_received;
    std::erase_if(waiting_,
                  [seen](const ResponsePtr& r) { return r->has_estimate() && r->estimate().frame_index() <= seen; });
    for (auto it = history_.rbegin(); it != history_.rend(); ++it) {
      if ((*it)->estimate().frame_index() > seen) waiting_.push_front(*it);
    }
  }
  waiting_.push_front(std::move(opened));
}

}  // namespace localizer::server
