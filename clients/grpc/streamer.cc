#include "clients/grpc/streamer.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <cstring>
#include <map>
#include <mutex>
#include <optional>
#include <thread>

#include "wire/block_wire.h"
#include "wire/estimate_wire.h"
#include "wire/status_wire.h"

namespace localizer::client {

namespace {

using Clock = std::chrono::steady_clock;

double SecondsBetween(Clock::time_point from, Clock::time_point to) {
  return std::chrono::duration<double>(to - from).count();
}

// When each block was handed to Write, until no later estimate can refer to it.
class SendLog {
 public:
  void Record(uint64_t sequence, Clock::time_point at) {
    std::lock_guard<std::mutex> lock(mutex_);
    sent_[sequence] = at;
  }
  // The send time of `sequence`; earlier entries are dropped (estimates arrive in order).
  std::optional<Clock::time_point> Lookup(uint64_t sequence) {
    std::lock_guard<std::mutex> lock(mutex_);
    sent_.erase(sent_.begin(), sent_.lower_bound(sequence));
    const auto it = sent_.find(sequence);
    if (it == sent_.end()) return std::nullopt;
    return it->second;
  }
  void Forget(uint64_t sequence) {
    std::lock_guard<std::mutex> lock(mutex_);
    sent_.erase(sequence);
  }

 private:
  std::mutex mutex_;
  std::map<uint64_t, Clock::time_point> sent_;  // guarded by mutex_
};

// The writer thread's side: source -> encode -> pace -> Write, then WritesDone.
class BlockWriter {
 public:
  BlockWriter(TrackStream& stream, const SampleSource& source, const StreamOptions& options, SendLog* log)
      : stream_(stream), source_(source), options_(options), log_(log) {}

  // Ends the pacing wait early; the next Write fails anyway once the stream is over.
  void Stop() {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
    wake_.notify_all();
  }

  void Run(Clock::time_point start) {
    uint64_t sequence = options_.first_sequence;
    const auto channels = static_cast<size_t>(options_.channel_count);
    while (!Stopped()) {
      auto n = source_(options_.block_samples, &samples_);
      if (!n.ok()) {
        status_ = n.status();
        break;
      }
      if (*n == 0) break;
      if (*n < 0 || *n > options_.block_samples || samples_.size() != channels * static_cast<size_t>(*n)) {
        status_ = Internal("the sample source returned " + std::to_string(*n) + " samples per channel in a buffer of " +
                           std::to_string(samples_.size()) + " values (block_samples " +
                           std::to_string(options_.block_samples) + ", " + std::to_string(channels) + " channels)");
        break;
      }
      engine::BlockView view;
      view.sequence = sequence;
      view.channel_count = options_.channel_count;
      view.samples_per_channel = *n;
      view.samples = samples_.data();
      wire::EncodeBlock(view, options_.encoding == Encoding::kPcm16, &block_);
      if (options_.pacing == Pacing::kRealtime && !WaitUntil(DueTime(start, *n))) break;
      log_->Record(sequence, Clock::now());
      if (!stream_.Write(block_)) break;  // the stream is over; the reader learns why
      samples_sent_ += *n;
      ++blocks_sent_;
      ++sequence;
    }
    // Half-close even after a source error: the server answers what it got and closes.
    if (!Stopped()) stream_.WritesDone();
  }

  const Status& status() const { return status_; }
  uint64_t blocks_sent() const { return blocks_sent_; }
  int64_t samples_sent() const { return samples_sent_; }

 private:
  bool Stopped() {
    std::lock_guard<std::mutex> lock(mutex_);
    return stop_;
  }
  // When the last sample of a block of n that follows samples_sent_ would be recorded.
  Clock::time_point DueTime(Clock::time_point start, int64_t n) const {
    const double at_s = static_cast<double>(samples_sent_ + n) / options_.sample_rate_hz;
    return start + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(at_s));
  }
  // False when stopped while waiting.
  bool WaitUntil(Clock::time_point due) {
    std::unique_lock<std::mutex> lock(mutex_);
    return !wake_.wait_until(lock, due, [this] { return stop_; });
  }

  TrackStream& stream_;
  const SampleSource& source_;
  const StreamOptions& options_;
  SendLog* log_;
  std::vector<float> samples_;  // one block, channel-major; reused
  v1::SampleBlock block_;       // one encoded block; reused
  Status status_;
  uint64_t blocks_sent_ = 0;
  int64_t samples_sent_ = 0;
  std::mutex mutex_;
  std::condition_variable wake_;
  bool stop_ = false;  // guarded by mutex_
};

StreamedEstimate FromWire(const v1::Estimate& wire_estimate) {
  StreamedEstimate e;
  e.estimate = wire::EstimateFromProto(wire_estimate);
  e.queue_s = wire_estimate.latency().queue_s();
  e.total_s = wire_estimate.latency().total_s();
  e.backend = wire_estimate.backend();
  return e;
}

// Reads until the stream ends, sorting responses into `result`.
void ReadResponses(TrackStream& stream, const StreamCallbacks& callbacks, SendLog* log, StreamResult* result) {
  v1::TrackResponse response;
  while (stream.Read(&response)) {
    const Clock::time_point received = Clock::now();
    switch (response.kind_case()) {
      case v1::TrackResponse::kEstimate: {
        StreamedEstimate e = FromWire(response.estimate());
        if (auto sent = log->Lookup(e.estimate.sequence)) {
          e.client_latency_s = SecondsBetween(*sent, received);
        }
        if (callbacks.on_estimate) callbacks.on_estimate(e);
        result->estimates.push_back(std::move(e));
        break;
      }
      case v1::TrackResponse::kRejected: {
        const v1::BlockRejected& r = response.rejected();
        BlockRejection rejection{r.sequence(), r.code(), r.reason(), r.message()};
        log->Forget(r.sequence());
        if (callbacks.on_rejected) callbacks.on_rejected(rejection);
        result->rejections.push_back(std::move(rejection));
        break;
      }
      case v1::TrackResponse::kGap:
        if (callbacks.on_gap) callbacks.on_gap(response.gap());
        result->gaps.push_back(response.gap());
        break;
      case v1::TrackResponse::kOpened:  // only first, and Open consumed it
      case v1::TrackResponse::kTracks:  // detection sessions only; a sample stream gets none
      case v1::TrackResponse::KIND_NOT_SET:
        break;
    }
  }
}

}  // namespace

SampleSource ChannelMajorSource(const float* samples, int channel_count, int64_t samples_per_channel) {
  int64_t next = 0;
  return [=](int64_t max_samples, std::vector<float>* out) mutable -> StatusOr<int64_t> {
    const int64_t n = std::clamp<int64_t>(samples_per_channel - next, 0, std::max<int64_t>(max_samples, 0));
    out->resize(static_cast<size_t>(channel_count) * static_cast<size_t>(n));
    for (int c = 0; c < channel_count; ++c) {
      const float* from = samples + c * samples_per_channel + next;
      std::copy(from, from + n, out->data() + c * n);
    }
    next += n;
    return n;
  };
}

StatusOr<Pacing> ParsePacing(const std::string& name) {
  if (name == "max") return Pacing::kMax;
  if (name == "realtime") return Pacing::kRealtime;
  return InvalidArgument("unknown rate \"" + name + "\"; use realtime or max");
}

StatusOr<Encoding> ParseEncoding(const std::string& name) {
  if (name == "float") return Encoding::kFloat32;
  if (name == "pcm16") return Encoding::kPcm16;
  return InvalidArgument("unknown encoding \"" + name + "\"; use float or pcm16");
}

Status StreamOptions::Validate() const {
  if (channel_count < 1) {
    return InvalidArgument("channel_count must be >= 1, got " + std::to_string(channel_count));
  }
  if (!(sample_rate_hz > 0.0) || !std::isfinite(sample_rate_hz)) {
    return InvalidArgument("sample_rate_hz must be finite and > 0, got " + std::to_string(sample_rate_hz));
  }
  if (block_samples < 1) {
    return InvalidArgument("block_samples must be >= 1, got " + std::to_string(block_samples));
  }
  if (first_sequence < 1) return InvalidArgument("first_sequence must be >= 1, got 0");
  return Status::Ok();
}

Status StreamResult::status() const {
  if (!client_status.ok()) return client_status;
  return wire::FromGrpcStatus(grpc_status);
}

std::vector<engine::Estimate> StreamResult::Estimates() const {
  std::vector<engine::Estimate> out;
  out.reserve(estimates.size());
  for (const StreamedEstimate& e : estimates) out.push_back(e.estimate);
  return out;
}

std::vector<double> StreamResult::ClientLatencies() const {
  std::vector<double> out;
  out.reserve(estimates.size());
  for (const StreamedEstimate& e : estimates) out.push_back(e.client_latency_s);
  return out;
}

StreamResult StreamBlocks(TrackStream& stream, const SampleSource& source, const StreamOptions& options,
                          const StreamCallbacks& callbacks) {
  StreamResult result;
  result.client_status = options.Validate();
  if (!result.client_status.ok()) {
    stream.Cancel();
    v1::TrackResponse ignored;
    while (stream.Read(&ignored)) {
    }
    result.grpc_status = stream.Finish();
    return result;
  }
  SendLog log;
  BlockWriter writer(stream, source, options, &log);
  const Clock::time_point start = Clock::now();
  std::thread writer_thread([&writer, start] { writer.Run(start); });
  ReadResponses(stream, callbacks, &log, &result);
  writer.Stop();  // the stream is over: a writer still pacing or reading gives up
  writer_thread.join();
  result.grpc_status = stream.Finish();
  result.wall_s = SecondsBetween(start, Clock::now());
  result.client_status = writer.status();
  result.blocks_sent = writer.blocks_sent();
  result.samples_sent_per_channel = writer.samples_sent();
  return result;
}

}  // namespace localizer::client
