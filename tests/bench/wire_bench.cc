// The server's own CPU per 64 KiB block outside the engine, piece by piece: parsing the
// request off the wire, de-interleaving (and checking) the samples, and turning each
// estimate into a response on the wire. gRPC's transport and the kernel are not in
// here; tests/bench/service_capacity.py measures the whole process.
//   build/tests/bench/wire_bench --benchmark_repetitions=5 --benchmark_report_aggregates_only=true
#include <benchmark/benchmark.h>

#include <cmath>
#include <random>

#include "engine/array/array_geometry.h"
#include "wire/block_wire.h"
#include "wire/estimate_wire.h"

namespace localizer::wire {
namespace {

constexpr int kChannels = 4;
constexpr int kSamples = 4096;  // per channel: 4 x 4096 float32 = 64 KiB

std::vector<float> Noise() {
  std::mt19937 rng(1);
  std::normal_distribution<float> normal(0.0f, 0.1f);
  std::vector<float> x(kChannels * kSamples);
  for (float& v : x) v = normal(rng);
  return x;
}

std::string SerializedBlock(bool pcm16) {
  const std::vector<float> x = Noise();
  v1::TrackRequest request;
  EncodeBlock({1, kChannels, kSamples, x.data()}, pcm16, request.mutable_block());
  return request.SerializeAsString();
}

void BM_ParseRequest(benchmark::State& state) {
  const std::string bytes = SerializedBlock(state.range(0) != 0);
  v1::TrackRequest request;
  for (auto _ : state) {
    request.ParseFromString(bytes);
    benchmark::DoNotOptimize(request.block().samples_size());
  }
  state.SetBytesProcessed(static_cast<int64_t>(state.iterations() * bytes.size()));
}
BENCHMARK(BM_ParseRequest)->Arg(0)->Arg(1)->ArgName("pcm16");

void BM_DecodeBlock(benchmark::State& state) {
  v1::TrackRequest request;
  request.ParseFromString(SerializedBlock(state.range(0) != 0));
  DecodedBlock out;
  std::string reason;
  for (auto _ : state) {
    benchmark::DoNotOptimize(DecodeBlock(request.block(), {kChannels, 1 << 20}, &out, &reason).ok());
  }
}
BENCHMARK(BM_DecodeBlock)->Arg(0)->Arg(1)->ArgName("pcm16");

void BM_EncodeEstimate(benchmark::State& state) {
  const auto array = *engine::ArrayGeometry::Create({{0, 0, 0}, {2, 0, 0}, {0, 2, 0}, {0, 0, 2}}, 1500.0);
  engine::Estimate e;
  e.initialised = true;
  e.state << 1, 2, 3, 0.1, 0.2, 0.3;
  e.covariance = engine::Mat6::Identity() * 0.01;
  e.delay_s = {1e-3, -2e-4, 5e-4};
  e.quality = {3.0, 2.5, 4.0};
  std::string bytes;
  for (auto _ : state) {
    v1::TrackResponse response;
    EstimateToProto(e, array.reference_sensor(), "cpu", response.mutable_estimate());
    response.SerializeToString(&bytes);
    benchmark::DoNotOptimize(bytes.data());
  }
  state.counters["bytes"] = static_cast<double>(bytes.size());
}
BENCHMARK(BM_EncodeEstimate);

}  // namespace
}  // namespace localizer::wire

BENCHMARK_MAIN();
