#include "server/service/session_host.h"

#include <time.h>

#include <algorithm>

#include "server/service/log.h"
#include "wire/config_wire.h"
#include "wire/estimate_wire.h"

namespace localizer::server {
namespace {

constexpr int kItemsPerTurn = 4;

double Seconds(Clock::duration d) { return std::chrono::duration<double>(d).count(); }

// CPU time of the calling thread: what the engine really costs, preemption excluded.
double ThreadCpuSeconds() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

void Observe(metrics::Histogram* h, double v) {
  if (h != nullptr) h->Observe(v);
}

void Bump(metrics::Counter* c, double v = 1.0) {
  if (c != nullptr) c->Increment(v);
}

ResponsePtr Rejection(uint64_t sequence, const std::string& reason, const Status& status,
                      const char* request = "block") {
  auto response = std::make_shared<v1::TrackResponse>();
  v1::BlockRejected* rejected = response->mutable_rejected();
  rejected->set_request(request);
  rejected->set_sequence(sequence);
  rejected->set_code(StatusCodeName(status.code()));
  rejected->set_message(status.message());
  rejected->set_reason(reason);
  return response;
}

}  // namespace

SessionHost::SessionHost(std::string id, std::string token, std::string label,
                         std::unique_ptr<engine::Session> session, HostLimits limits, WorkerPool* pool,
                         ServiceMetrics* metrics)
    : id_(std::move(id)),
      token_(std::move(token)),
      label_(std::move(label)),
      session_(std::move(session)),
      config_(session_->config()),
      backend_(session_->backend()),
      limits_(limits),
      block_limits_{session_->array().sensor_count(), session_->config().max_block_samples},
      pool_(pool),
      metrics_(metrics),
      created_(Clock::now()),
      detached_since_(created_),
      last_block_(created_) {}

SessionHost::SessionHost(std::string id, std::string token, std::string label,
                         std::unique_ptr<engine::ScanSession> scans, HostLimits limits, WorkerPool* pool,
                         ServiceMetrics* metrics)
    : id_(std::move(id)),
      token_(std::move(token)),
      label_(std::move(label)),
      scans_(std::move(scans)),
      config_(),
      backend_("cpu"),
      limits_(limits),
      block_limits_{0, 0},  // takes no sample blocks
      pool_(pool),
      metrics_(metrics),
      created_(Clock::now()),
      detached_since_(created_),
      last_block_(created_) {}

SessionHost::~SessionHost() {
  std::lock_guard<std::mutex> lock(mutex_);
  metrics_->queue_depth->Add(-static_cast<double>(queued_blocks_));
}

bool SessionHost::TokenMatches(const std::string& token) const {
  if (token.size() != token_.size()) return false;
  unsigned char diff = 0;
  for (size_t i = 0; i < token.size(); ++i) diff |= static_cast<unsigned char>(token[i] ^ token_[i]);
  return diff == 0;
}

v1::SessionOpened SessionHost::OpenedMessageLocked(bool resumed) const {
  v1::SessionOpened opened;
  opened.set_session_id(id_);
  opened.set_resume_token(token_);
  v1::SessionConfig* effective = opened.mutable_effective_config();
  *effective =
      session_ ? wire::ConfigToProto(session_->config(), label_) : wire::ConfigToProto(scans_->config(), label_);
  effective->set_backend(backend_);
  opened.set_backend(backend_);
  opened.set_resumed(resumed);
  if (last_accepted_) opened.set_last_sequence(*last_accepted_);
  opened.set_frames_processed(frames_);
  opened.set_session_ttl_s(limits_.ttl_s);
  return opened;
}

void SessionHost::AttachLocked(StreamSink* sink, bool resumed, std::optional<uint64_t> last_frame_received,
                               bool received_none) {
  if (sink_ != nullptr && sink_ != sink) {
    StreamSink* old = sink_;
    sink_ = nullptr;
    // Its write in flight may never reach the client: it goes first again (the replay
    // below drops it if the client says it has it).
    if (ResponsePtr in_flight = old->TakeInFlightLocked()) RequeueLocked(std::move(in_flight));
    old->EndLocked(grpc::Status(grpc::StatusCode::ABORTED, "session " + id_ + " was resumed on another stream"));
    Bump(metrics_->sessions_closed("replaced"));
  }
  sink_ = sink;
  input_paused_ = false;
  if (received_none) {
    // The client has nothing: replay every written estimate still held, oldest first.
    for (auto it = history_.rbegin(); it != history_.rend(); ++it) outbox_.push_front(*it);
  } else if (last_frame_received) {
    // Drop what the client has; replay written estimates it has not seen, oldest first.
    const uint64_t seen = *last_frame_received;
    std::erase_if(outbox_, [seen](const ResponsePtr& r) {
      return r->has_estimate() && r->estimate().frame_index() <= seen;
    });
    for (auto it = history_.rbegin(); it != history_.rend(); ++it) {
      if ((*it)->estimate().frame_index() > seen) outbox_.push_front(*it);
    }
  }
  auto opened = std::make_shared<v1::TrackResponse>();
  *opened->mutable_opened() = OpenedMessageLocked(resumed);
  outbox_.push_front(std::move(opened));
  sink_->OutputReadyLocked();
}

void SessionHost::DetachLocked(StreamSink* sink) {
  if (sink_ != sink || sink == nullptr) return;
  sink_ = nullptr;
  detached_since_ = Clock::now();
}

bool SessionHost::attached() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return sink_ != nullptr;
}

void SessionHost::RejectLocked(uint64_t sequence, const std::string& reason, const Status& status,
                               Clock::time_point received) {
  ++rejections_;
  Bump(metrics_->rejections(reason));
  LogEvent("debug", "block_rejected", {{"session", id_}, {"sequence", std::to_string(sequence)}, {"reason", reason}});
  // In order behind the blocks already queued, so responses keep the blocks' order.
  WorkItem item;
  item.sequence = sequence;
  item.response = Rejection(sequence, reason, status);
  item.received = received;
  queue_.push_back(std::move(item));
  ScheduleLocked();
}

bool SessionHost::OfferLocked(wire::DecodedBlock* decoded, const Status& decode_status, const std::string& reason,
                              uint64_t sequence, Clock::time_point received) {
  if (closed_) return false;
  if (scans_ != nullptr) {
    RejectLocked(sequence, "not_samples",
                 FailedPrecondition("a sample block for a detection session (it takes scans)"), received);
  } else if (!decode_status.ok()) {
    RejectLocked(sequence, reason, decode_status, received);
  } else if (last_accepted_ && sequence <= *last_accepted_) {
    const bool duplicate = sequence == *last_accepted_;
    const std::string message =
        "sequence " + std::to_string(sequence) +
        (duplicate ? " repeats the last accepted block's" : " is below the last accepted block's " +
                                                                 std::to_string(*last_accepted_)) +
        "; the block was ignored";
    RejectLocked(sequence, duplicate ? "duplicate" : "out_of_order", InvalidArgument(message), received);
  } else {
    WorkItem item;
    item.sequence = sequence;
    item.samples_per_channel = decoded->view.samples_per_channel;
    item.received = received;
    if (last_accepted_ && sequence > *last_accepted_ + 1) {
      const uint64_t missing = sequence - *last_accepted_ - 1;
      auto gap = std::make_shared<v1::TrackResponse>();
      v1::SequenceGap* g = gap->mutable_gap();
      g->set_previous_sequence(*last_accepted_);
      g->set_sequence(sequence);
      g->set_missing_blocks(missing);
      const uint64_t skip = std::min<uint64_t>(missing, uint64_t{1} << 20) *
                            static_cast<uint64_t>(item.samples_per_channel);
      g->set_skipped_samples(skip);
      item.skip_samples = static_cast<int64_t>(std::min<uint64_t>(skip, uint64_t{1} << 40));
      item.response = std::move(gap);
      Bump(metrics_->gaps);
    }
    item.samples = std::move(decoded->samples);
    if (!free_buffers_.empty()) {
      decoded->samples = std::move(free_buffers_.back());
      free_buffers_.pop_back();
    } else {
      decoded->samples.clear();
    }
    last_accepted_ = sequence;
    last_block_ = received;
    ++queued_blocks_;
    metrics_->queue_depth->Increment();
    queue_.push_back(std::move(item));
    ScheduleLocked();
  }
  // Rejections occupy slots too: a client sending only bad blocks is held back as well.
  const bool room = queue_.size() < static_cast<size_t>(limits_.max_queue_blocks);
  input_paused_ = !room;
  return room;
}

bool SessionHost::OfferImuLocked(StatusOr<wire::DecodedImu> decoded, uint64_t batch_sequence,
                                 Clock::time_point received) {
  if (closed_) return false;
  WorkItem item;
  item.received = received;
  if (!config_.array_in_body_frame) {
    Bump(metrics_->rejections("not_moving"));
    item.response = Rejection(batch_sequence, "not_moving",
                              FailedPrecondition("imu batch for a session whose array is fixed in the world (open "
                                                 "it with SessionConfig.platform)"),
                              "imu");
  } else if (!decoded.ok()) {
    Bump(metrics_->rejections("imu"));
    item.response = Rejection(batch_sequence, "imu", decoded.status(), "imu");
  } else {
    item.imu = std::move(decoded).value();
    item.imu_sequence = batch_sequence;
  }
  return QueueLocked(std::move(item));
}

bool SessionHost::OfferScanLocked(StatusOr<engine::Scan> decoded, uint64_t scan_sequence, Clock::time_point received) {
  if (closed_) return false;
  WorkItem item;
  item.received = received;
  if (scans_ == nullptr) {
    Bump(metrics_->rejections("not_detections"));
    item.response = Rejection(scan_sequence, "not_detections",
                              FailedPrecondition("a scan for an audio session (open it with SessionConfig.detections)"),
                              "scan");
  } else if (!decoded.ok()) {
    Bump(metrics_->rejections("scan"));
    item.response = Rejection(scan_sequence, "scan", decoded.status(), "scan");
  } else {
    item.scan = std::move(decoded).value();
    item.scan_sequence = scan_sequence;
    last_block_ = received;  // a detection session's activity is its scans
  }
  return QueueLocked(std::move(item));
}

bool SessionHost::QueueLocked(WorkItem item) {
  queue_.push_back(std::move(item));
  ScheduleLocked();
  const bool room = queue_.size() < static_cast<size_t>(limits_.max_queue_blocks);
  input_paused_ = !room;
  return room;
}

void SessionHost::ScheduleLocked() {
  if (scheduled_ || closed_ || queue_.empty() || outbox_.size() >= limits_.max_outbox) return;
  scheduled_ = true;
  if (!pool_->Submit([self = shared_from_this()] { self->RunTurn(); })) scheduled_ = false;
}

void SessionHost::RunTurn() {
  for (int n = 0; n < kItemsPerTurn; ++n) {
    WorkItem item;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      if (closed_ || queue_.empty() || outbox_.size() >= limits_.max_outbox) break;
      item = std::move(queue_.front());
      queue_.pop_front();
      running_ = true;
      if (item.samples_per_channel > 0) {  // the block leaves the queue: room for the next
        --queued_blocks_;
        metrics_->queue_depth->Decrement();
      }
    }
    std::vector<ResponsePtr> responses = Process(item, Clock::now());
    std::lock_guard<std::mutex> lock(mutex_);
    running_ = false;
    if (item.samples_per_channel > 0) {
      ++blocks_;
      // Recycled with its size: a block of the same length reuses it without zero-filling.
      if (free_buffers_.size() < 4) free_buffers_.push_back(std::move(item.samples));
    }
    for (ResponsePtr& r : responses) PushOutputLocked(std::move(r));
    if (sink_ != nullptr) {
      if (input_paused_ && queue_.size() < static_cast<size_t>(limits_.max_queue_blocks)) {
        input_paused_ = false;
        sink_->InputSpaceLocked();
      }
      sink_->OutputReadyLocked();
    }
  }
  std::lock_guard<std::mutex> lock(mutex_);
  scheduled_ = false;
  ScheduleLocked();
  if (sink_ != nullptr && IdleLocked()) sink_->OutputReadyLocked();
}

std::vector<ResponsePtr> SessionHost::ProcessScan(WorkItem& item) {
  std::vector<ResponsePtr> out;
  engine::ScanResult result;
  const double cpu_start_s = ThreadCpuSeconds();
  const Status status = scans_->Process(*item.scan, &result);
  Bump(metrics_->engine_cpu, ThreadCpuSeconds() - cpu_start_s);
  if (!status.ok()) {  // out of time order, or a plot the tracker refuses
    Bump(metrics_->rejections("scan"));
    out.push_back(Rejection(item.scan_sequence, "scan", status, "scan"));
    return out;
  }
  auto response = std::make_shared<v1::TrackResponse>();
  v1::TrackList* list = response->mutable_tracks();
  wire::TrackListToProto(result, item.scan_sequence, list);
  const double total_s = Seconds(Clock::now() - item.received);
  list->set_total_s(total_s);
  Bump(metrics_->scans);
  Bump(metrics_->track_updates, static_cast<double>(result.summary.track_updates));
  Observe(metrics_->scan_tracker, result.process_s);
  Observe(metrics_->scan_total, total_s);
  track_.SetTargets(result.tracks);
  out.push_back(std::move(response));
  return out;
}

std::vector<ResponsePtr> SessionHost::Process(WorkItem& item, Clock::time_point started) {
  std::vector<ResponsePtr> out;
  if (item.response) out.push_back(item.response);
  if (item.scan) {
    for (ResponsePtr& r : ProcessScan(item)) out.push_back(std::move(r));
    return out;
  }
  if (item.imu) {
    // Ordering against the previous batch is the engine's check (the reader cannot know).
    Status status = session_->AddImu(item.imu->samples);
    if (status.ok() && item.imu->origin_m) status = session_->SetPlatformOrigin(*item.imu->origin_m);
    if (!status.ok()) {
      Bump(metrics_->rejections("imu"));
      out.push_back(Rejection(item.imu_sequence, "imu", status, "imu"));
    }
    return out;
  }
  if (item.samples_per_channel == 0) return out;
  const StageHistograms& stages = metrics_->stages(session_->backend());
  Observe(stages.queue, Seconds(started - item.received));
  if (item.skip_samples > 0) (void)session_->Skip(item.skip_samples);
  engine::BlockView view;
  view.sequence = item.sequence;
  view.channel_count = block_limits_.channel_count;
  view.samples_per_channel = item.samples_per_channel;
  view.samples = item.samples.data();
  estimates_.clear();
  const double cpu_start_s = ThreadCpuSeconds();
  const Status status = session_->Process(view, &estimates_);
  Bump(metrics_->engine_cpu, ThreadCpuSeconds() - cpu_start_s);
  if (!status.ok()) {
    // The reader validated the block; the engine refusing it is unexpected but answered.
    Bump(metrics_->rejections("engine"));
    out.push_back(Rejection(item.sequence, "engine", status));
    return out;
  }
  Bump(metrics_->blocks);
  Bump(metrics_->samples, static_cast<double>(item.samples_per_channel));
  const Clock::time_point done = Clock::now();
  for (const engine::Estimate& e : estimates_) {
    auto response = std::make_shared<v1::TrackResponse>();
    v1::Estimate* wire_estimate = response->mutable_estimate();
    wire::EstimateToProto(e, session_->array(), session_->backend(), wire_estimate);
    wire_estimate->mutable_latency()->set_queue_s(Seconds(started - item.received));
    wire_estimate->mutable_latency()->set_total_s(Seconds(done - item.received));
    Observe(stages.tdoa, e.timings.tdoa_s);
    Observe(stages.filter, e.timings.filter_s);
    Observe(stages.total, Seconds(done - item.received));
    Bump(stages.estimates);
    track_.Append(e);
    out.push_back(std::move(response));
  }
  return out;
}

void SessionHost::PushOutputLocked(ResponsePtr response) {
  if (response->has_estimate() || response->has_tracks()) ++frames_;
  outbox_.push_back(std::move(response));
}

ResponsePtr SessionHost::NextOutputLocked() {
  if (outbox_.empty()) return nullptr;
  ResponsePtr r = std::move(outbox_.front());
  outbox_.pop_front();
  return r;
}

void SessionHost::MarkWrittenLocked(const ResponsePtr& response) {
  if (response->has_estimate()) {
    history_.push_back(response);
    if (history_.size() > kHistoryEstimates) history_.pop_front();
  }
  ScheduleLocked();  // the outbox shrank: processing may have paused on it
}

void SessionHost::RequeueLocked(ResponsePtr response) {
  if (response->has_opened()) return;  // a resume sends a fresh one
  outbox_.push_front(std::move(response));
}

void SessionHost::Close(const grpc::Status& status) {
  std::lock_guard<std::mutex> lock(mutex_);
  CloseLocked(status);
}

void SessionHost::CloseLocked(const grpc::Status& status) {
  if (closed_) return;
  closed_ = true;
  metrics_->queue_depth->Add(-static_cast<double>(queued_blocks_));
  queued_blocks_ = 0;
  queue_.clear();
  if (sink_ != nullptr) {
    StreamSink* sink = sink_;
    sink_ = nullptr;
    sink->EndLocked(status);
  }
}

void SessionHost::Drain() {
  std::lock_guard<std::mutex> lock(mutex_);
  if (sink_ != nullptr) sink_->DrainLocked();
}

bool SessionHost::Drained() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return closed_ || (IdleLocked() && (sink_ == nullptr || outbox_.empty()));
}

bool SessionHost::ExpiredLocked(Clock::time_point now, double ttl_s) const {
  return sink_ == nullptr && Seconds(now - detached_since_) > ttl_s;
}

v1::SessionInfo SessionHost::Info(Clock::time_point now, double ttl_s) const {
  std::lock_guard<std::mutex> lock(mutex_);
  v1::SessionInfo info;
  info.set_session_id(id_);
  info.set_label(label_);
  info.set_backend(backend_);
  info.set_attached(sink_ != nullptr);
  info.set_channel_count(static_cast<uint32_t>(block_limits_.channel_count));
  info.set_sample_rate_hz(config_.sample_rate_hz);
  info.set_blocks_processed(blocks_);
  info.set_frames_processed(frames_);
  info.set_rejections(rejections_);
  if (last_accepted_) info.set_last_sequence(*last_accepted_);
  info.set_age_s(Seconds(now - created_));
  info.set_idle_s(Seconds(now - last_block_));
  info.set_queued_blocks(static_cast<uint32_t>(queued_blocks_));
  if (sink_ == nullptr) info.set_expires_in_s(std::max(0.0, ttl_s - Seconds(now - detached_since_)));
  return info;
}

}  // namespace localizer::server
