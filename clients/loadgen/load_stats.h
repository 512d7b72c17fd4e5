// The counters every session of a load run adds to, read by the progress line and the
// result. Counters are relaxed atomics (sessions run on gRPC's threads and the pacing
// threads); the tallies by name (status codes, rejection reasons, backends) change rarely
// and sit behind a mutex.
#pragma once

#include <atomic>
#include <cstdint>
#include <map>
#include <mutex>
#include <string>

#include "clients/loadgen/latency_histogram.h"

namespace localizer::loadgen {

// A tally by name: "UNAVAILABLE" -> 3.
using Tally = std::map<std::string, int64_t>;

class LoadStats {
 public:
  std::atomic<int64_t> started{0};        // sessions whose stream was started
  std::atomic<int64_t> opened{0};         // sessions the server answered with `opened`
  std::atomic<int64_t> live{0};           // opened and not yet ended
  std::atomic<int64_t> finished{0};       // sessions over (ended, or never started)
  std::atomic<int64_t> blocks_sent{0};    // blocks handed to gRPC
  std::atomic<int64_t> estimates{0};      // estimates received
  std::atomic<int64_t> unmatched{0};      // estimates naming a block this run has no send time for
  std::atomic<int64_t> initialised{0};    // estimates of a filter that has a fix (the engine tracks)
  std::atomic<int64_t> present{0};        // estimates whose frame holds a source (source_present)
  std::atomic<int64_t> gaps{0};           // SequenceGap responses
  std::atomic<int64_t> late_blocks{0};    // realtime: handed to gRPC over one block period after due
  std::atomic<int64_t> behind_max_ns{0};  // realtime: the most a block was behind its due time
  std::atomic<int64_t> first_send_ns{-1};
  std::atomic<int64_t> last_send_ns{-1};
  std::atomic<int64_t> last_estimate_ns{-1};
  LatencyHistogram latency;  // block handed to gRPC -> each of its estimates read

  void CountError(const std::string& code) { Increment(&errors_, code); }
  void CountRejection(const std::string& reason) { Increment(&rejections_, reason); }
  void CountBackend(const std::string& backend) { Increment(&backends_, backend); }
  void NoteSend(int64_t now_ns);
  void NoteEstimate(int64_t now_ns) { Max(&last_estimate_ns, now_ns); }
  void NoteBehind(int64_t behind_ns) { Max(&behind_max_ns, behind_ns); }

  Tally errors() const { return Copy(errors_); }
  Tally rejections() const { return Copy(rejections_); }
  Tally backends() const { return Copy(backends_); }
  static int64_t Sum(const Tally& tally);

 private:
  void Increment(Tally* tally, const std::string& key);
  Tally Copy(const Tally& tally) const;
  static void Max(std::atomic<int64_t>* value, int64_t candidate);

  mutable std::mutex mutex_;
  Tally errors_;      // guarded by mutex_: streams that ended in an error, by status code
  Tally rejections_;  // guarded by mutex_: BlockRejected by reason; refused sessions
  Tally backends_;    // guarded by mutex_: SessionOpened.backend
};

}  // namespace localizer::loadgen
