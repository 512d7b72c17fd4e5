#include "clients/loadgen/load_run.h"

#include <sys/resource.h>

#include <chrono>
#include <memory>
#include <thread>
#include <vector>

#include "clients/grpc/connection.h"
#include "clients/loadgen/load_report.h"
#include "clients/loadgen/load_session.h"
#include "clients/loadgen/pacer.h"
#include "clients/loadgen/workload.h"

namespace localizer::loadgen {

namespace {

constexpr double kConnectTimeoutS = 10.0;

struct CpuTimes {
  double user_s = 0.0;
  double system_s = 0.0;
};

CpuTimes ProcessCpu() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  auto seconds = [](const timeval& t) { return static_cast<double>(t.tv_sec) + 1e-6 * static_cast<double>(t.tv_usec); };
  return {seconds(usage.ru_utime), seconds(usage.ru_stime)};
}

}  // namespace

StatusOr<nlohmann::json> RunLoad(const LoadOptions& options, const std::atomic<bool>& stop,
                                 const std::function<void(const std::string&)>& progress) {
  const Workload workload(options);

  const int connection_count = options.connection_count();
  client::ConnectOptions connect = options.connect;
  connect.own_connection = true;
  std::vector<std::shared_ptr<grpc::Channel>> channels;
  std::vector<std::unique_ptr<TrackStub>> stubs;
  for (int c = 0; c < connection_count; ++c) {
    auto channel = client::Connect(options.target, connect);
    if (!channel.ok()) return channel.status();
    const Status connected = client::WaitConnected(*channel, kConnectTimeoutS);
    if (!connected.ok()) return Unavailable(connected.message() + " (" + options.target + ")");
    channels.push_back(*channel);
    stubs.push_back(std::make_unique<TrackStub>(*channel));
  }

  LoadStats stats;
  const SessionShared shared{&options, &workload, &stats, &stop};
  const double spread_s = options.ramp_s > 0.0
                              ? options.ramp_s
                              : (options.pacing == client::Pacing::kRealtime ? options.block_period_s() : 0.0);
  const int64_t t0_ns = NowNs() + 50'000'000;  // time to start the pacing threads
  std::vector<std::unique_ptr<LoadSession>> sessions;
  std::vector<std::vector<LoadSession*>> per_thread(options.threads);
  for (int i = 0; i < options.sessions; ++i) {
    const auto offset_ns = static_cast<int64_t>(1e9 * spread_s * i / options.sessions);
    sessions.push_back(std::make_unique<LoadSession>(i, t0_ns + offset_ns, stubs[i % connection_count].get(), shared));
    per_thread[i % options.threads].push_back(sessions.back().get());
  }

  const CpuTimes cpu0 = ProcessCpu();
  std::vector<std::unique_ptr<Pacer>> pacers;
  for (auto& group : per_thread) {
    pacers.push_back(std::make_unique<Pacer>(group, &stop));
    pacers.back()->Start();
  }

  // Progress each second until every session is over; polled every 50 ms, so the run's end
  // is seen within that.
  LatencyCounts previous = stats.latency.Snapshot();
  int64_t next_print_ns = t0_ns + 1'000'000'000;
  while (stats.finished.load(std::memory_order_acquire) < options.sessions) {
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
    const int64_t now_ns = NowNs();
    if (now_ns >= next_print_ns) {
      const LatencyCounts all = stats.latency.Snapshot();
      progress(ProgressLine(1e-9 * static_cast<double>(now_ns - t0_ns), options, stats, all.Minus(previous), all));
      previous = all;
      next_print_ns += 1'000'000'000;
    }
  }
  for (auto& pacer : pacers) pacer->Join();
  const CpuTimes cpu1 = ProcessCpu();

  RunFacts facts;
  facts.connections = connection_count;
  facts.wall_s = 1e-9 * static_cast<double>(NowNs() - t0_ns);
  facts.cpu_user_s = cpu1.user_s - cpu0.user_s;
  facts.cpu_system_s = cpu1.system_s - cpu0.system_s;
  facts.interrupted = stop.load();
  return ResultJson(options, stats, facts);
}

}  // namespace localizer::loadgen
