#include "gpu/srp/srp_batch.h"

#include <cuda_runtime_api.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <string>

#include "gpu/core/cuda_status.h"
#include "gpu/core/device.h"
#include "gpu/core/device_buffer.h"
#include "gpu/srp/srp_kernels.h"

namespace localizer::gpu {
namespace {

constexpr int kMaxSessions = 1 << 20;
// The map's launch has a block row per 256 directions, at most 65535 rows.
constexpr int kMaxDirections = 1 << 22;

bool AllFinite(const float* v, size_t n) {
  uint32_t non_finite = 0;  // an all-ones exponent: inf or NaN (integer ops, so the loop vectorises)
  for (size_t i = 0; i < n; ++i)
    non_finite |= static_cast<uint32_t>((std::bit_cast<uint32_t>(v[i]) & 0x7f800000u) == 0x7f800000u);
  return non_finite == 0;
}

template <typename T>
StatusOr<DeviceBuffer<T>> Upload(const std::vector<T>& host, cudaStream_t stream, const char* what) {
  auto buffer = DeviceBuffer<T>::Allocate(host.size());
  if (!buffer.ok()) return buffer.status();
  if (!host.empty()) {
    LOCALIZER_CUDA_RETURN_IF_ERROR(
        cudaMemcpyAsync(buffer->data(), host.data(), host.size() * sizeof(T), cudaMemcpyHostToDevice, stream), what);
  }
  return buffer;
}

}  // namespace

struct SrpBatch::Impl {
  std::vector<SrpArrayModel> arrays;
  std::vector<std::vector<engine::Vec3>> directions;
  std::vector<bool> refine;
  int max_sessions = 0;
  int max_spectrum_floats = 0, max_directions = 0, max_pairs = 0;
  bool collect_timing = false;
  Timing last;

  CudaStream stream;
  DeviceBuffer<SrpArrayDesc> d_arrays;
  DeviceBuffer<float> d_directions, d_lags;
  DeviceBuffer<double> d_lags_double;
  DeviceBuffer<SrpSessionTask> d_tasks;
  PinnedBuffer<SrpSessionTask> h_tasks;
  DeviceBuffer<float> d_spectra, d_map;
  PinnedBuffer<float> h_spectra, h_map;
  DeviceBuffer<SrpSessionResult> d_results;
  PinnedBuffer<SrpSessionResult> h_results;
  cudaEvent_t events[4] = {nullptr, nullptr, nullptr, nullptr};

  ~Impl() {
    for (cudaEvent_t e : events)
      if (e != nullptr) cudaEventDestroy(e);
  }
};

SrpBatch::SrpBatch(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
SrpBatch::~SrpBatch() = default;

StatusOr<std::unique_ptr<SrpBatch>> SrpBatch::Create(std::vector<SrpArrayConfig> arrays, int max_sessions,
                                                     bool collect_timing) {
  if (arrays.empty()) return InvalidArgument("the SRP batch needs at least one array");
  if (max_sessions < 1 || max_sessions > kMaxSessions)
    return InvalidArgument("max_sessions must be in [1, " + std::to_string(kMaxSessions) + "], got " +
                           std::to_string(max_sessions));
  auto impl = std::make_unique<Impl>();
  impl->max_sessions = max_sessions;
  impl->collect_timing = collect_timing;
  // Host-side descriptions first: a bad configuration is INVALID_ARGUMENT with or without a device.
  std::vector<float> directions, lags;
  std::vector<double> lags_double;
  std::vector<SrpArrayDesc> descs;
  for (size_t a = 0; a < arrays.size(); ++a) {
    const SrpArrayConfig& config = arrays[a];
    const std::string name = "array " + std::to_string(a) + ": ";
    StatusOr<SrpArrayModel> model = MakeSrpArrayModel(config.sensors_m, config.options);
    if (!model.ok()) return InvalidArgument(name + model.status().message());
    if (config.directions.empty() || config.directions.size() > static_cast<size_t>(kMaxDirections))
      return InvalidArgument(name + "the direction grid must hold 1 to " + std::to_string(kMaxDirections) +
                             " directions, not " + std::to_string(config.directions.size()));
    std::vector<engine::Vec3> grid;
    for (size_t d = 0; d < config.directions.size(); ++d) {
      const engine::Vec3& u = config.directions[d];
      if (!u.allFinite() || !(u.norm() > 0.0))
        return InvalidArgument(name + "direction " + std::to_string(d) + " is not a finite non-zero vector");
      grid.push_back(u.normalized());
    }
    SrpArrayDesc desc;
    desc.band = model->band;
    desc.pairs = model->pairs;
    desc.directions = static_cast<int32_t>(grid.size());
    desc.refine = config.refine ? 1 : 0;
    desc.z_per_power = model->z_per_power;
    desc.directions_offset = static_cast<int64_t>(directions.size() / 3);
    desc.lag_offset = static_cast<int64_t>(lags.size());
    desc.geometry = model->Geometry();
    desc.geometry.lag_per_direction = nullptr;  // the device copy's address, below
    for (const engine::Vec3& u : grid)
      directions.insert(directions.end(), {static_cast<float>(u.x()), static_cast<float>(u.y()), static_cast<float>(u.z())});
    for (double d : model->lag_per_direction) lags.push_back(static_cast<float>(d));
    lags_double.insert(lags_double.end(), model->lag_per_direction.begin(), model->lag_per_direction.end());
    impl->max_spectrum_floats = std::max(impl->max_spectrum_floats, model->spectrum_floats());
    impl->max_directions = std::max(impl->max_directions, desc.directions);
    impl->max_pairs = std::max(impl->max_pairs, model->pairs);
    descs.push_back(desc);
    impl->arrays.push_back(std::move(*model));
    impl->directions.push_back(std::move(grid));
    impl->refine.push_back(config.refine);
  }

  if (const std::string& reason = DeviceUnavailableReason(); !reason.empty())
    return FailedPrecondition("no usable GPU for the SRP batch: " + reason);
  LOCALIZER_RETURN_IF_ERROR(PrepareSrpMap(SrpMapSharedBytes(impl->max_spectrum_floats, impl->max_pairs)));
  auto stream = CudaStream::Create();
  if (!stream.ok()) return stream.status();
  impl->stream = std::move(*stream);
  const cudaStream_t s = impl->stream.get();

  auto d_directions = Upload(directions, s, "cudaMemcpyAsync(SRP directions)");
  if (!d_directions.ok()) return d_directions.status();
  impl->d_directions = std::move(*d_directions);
  auto d_lags = Upload(lags, s, "cudaMemcpyAsync(SRP lags)");
  if (!d_lags.ok()) return d_lags.status();
  impl->d_lags = std::move(*d_lags);
  auto d_lags_double = Upload(lags_double, s, "cudaMemcpyAsync(SRP lags, double)");
  if (!d_lags_double.ok()) return d_lags_double.status();
  impl->d_lags_double = std::move(*d_lags_double);
  for (SrpArrayDesc& desc : descs) desc.geometry.lag_per_direction = impl->d_lags_double.data() + desc.lag_offset;
  auto d_arrays = Upload(descs, s, "cudaMemcpyAsync(SRP arrays)");
  if (!d_arrays.ok()) return d_arrays.status();
  impl->d_arrays = std::move(*d_arrays);

  const auto sessions = static_cast<size_t>(max_sessions);
  const size_t spectra = sessions * static_cast<size_t>(impl->max_spectrum_floats);
  const size_t map = sessions * static_cast<size_t>(impl->max_directions);
#define LOCALIZER_SRP_ALLOCATE(member, type, count)    \
  do {                                                 \
    auto buffer = type::Allocate(count);               \
    if (!buffer.ok()) return buffer.status();          \
    impl->member = std::move(*buffer);                 \
  } while (false)
  LOCALIZER_SRP_ALLOCATE(d_tasks, DeviceBuffer<SrpSessionTask>, sessions);
  LOCALIZER_SRP_ALLOCATE(h_tasks, PinnedBuffer<SrpSessionTask>, sessions);
  LOCALIZER_SRP_ALLOCATE(d_spectra, DeviceBuffer<float>, spectra);
  LOCALIZER_SRP_ALLOCATE(h_spectra, PinnedBuffer<float>, spectra);
  LOCALIZER_SRP_ALLOCATE(d_map, DeviceBuffer<float>, map);
  LOCALIZER_SRP_ALLOCATE(h_map, PinnedBuffer<float>, map);
  LOCALIZER_SRP_ALLOCATE(d_results, DeviceBuffer<SrpSessionResult>, sessions);
  LOCALIZER_SRP_ALLOCATE(h_results, PinnedBuffer<SrpSessionResult>, sessions);
#undef LOCALIZER_SRP_ALLOCATE
  if (collect_timing) {
    for (cudaEvent_t& e : impl->events) LOCALIZER_CUDA_RETURN_IF_ERROR(cudaEventCreate(&e), "cudaEventCreate(SRP)");
  }
  LOCALIZER_RETURN_IF_ERROR(impl->stream.Synchronize());  // the uploads above
  return std::unique_ptr<SrpBatch>(new SrpBatch(std::move(impl)));
}

SrpPeak DescribeSrpResult(const SrpArrayModel& model, const SrpSessionResult& r) {
  SrpPeak peak;
  peak.grid_index = r.grid_index;
  peak.grid_z = r.grid_z;
  peak.statistic = r.z;
  peak.threshold = model.threshold;
  peak.iterations = r.iterations;
  if (r.grid_index < 0) return peak;  // the map held no number
  if (model.shape.shape == engine::ArrayShape::kLinear) {
    peak.cone_angle_rad = r.theta_rad;
    return peak;
  }
  engine::Vec3 u(r.ux, r.uy, r.uz);
  if (model.shape.shape == engine::ArrayShape::kPlanar) {  // as SrpPhat::Describe
    const engine::PlanarDirection resolved = engine::ResolvePlanarMirror(u, model.shape.axis, model.source_side);
    u = resolved.direction;
    peak.mirror_ambiguous = resolved.mirror_ambiguous;
    peak.mirror_direction = resolved.mirror_direction;
  }
  peak.direction = u;
  return peak;
}

Status SrpBatch::Run(std::span<const SrpJob> jobs) {
  Impl& m = *impl_;
  if (jobs.empty()) return InvalidArgument("the SRP batch was given no job");
  if (jobs.size() > static_cast<size_t>(m.max_sessions))
    return InvalidArgument(std::to_string(jobs.size()) + " jobs exceed the batch's " +
                           std::to_string(m.max_sessions) + " sessions");
  int64_t spectra_floats = 0, map_floats = 0;
  bool want_map = false;
  for (size_t j = 0; j < jobs.size(); ++j) {
    const SrpJob& job = jobs[j];
    const std::string name = "job " + std::to_string(j) + ": ";
    if (job.array < 0 || job.array >= static_cast<int>(m.arrays.size()))
      return InvalidArgument(name + "array " + std::to_string(job.array) + " is not one of the batch's " +
                             std::to_string(m.arrays.size()));
    if (job.spectra == nullptr || job.out == nullptr) return InvalidArgument(name + "null spectra or out");
    const SrpArrayModel& model = m.arrays[static_cast<size_t>(job.array)];
    const auto n = static_cast<size_t>(model.spectrum_floats());
    float* staged = m.h_spectra.data() + spectra_floats;
    std::memcpy(staged, job.spectra, n * sizeof(float));
    if (!AllFinite(staged, n)) return InvalidArgument(name + "the spectra hold a non-finite value (NaN or Inf)");
    SrpSessionTask& task = m.h_tasks.data()[j];
    task.array = job.array;
    task.spectra_offset = spectra_floats;
    task.map_offset = map_floats;
    spectra_floats += static_cast<int64_t>(n);
    map_floats += static_cast<int64_t>(m.directions[static_cast<size_t>(job.array)].size());
    want_map = want_map || job.map_z != nullptr;
  }
  const cudaStream_t s = m.stream.get();
  const int sessions = static_cast<int>(jobs.size());
  if (m.collect_timing) LOCALIZER_CUDA_RETURN_IF_ERROR(cudaEventRecord(m.events[0], s), "cudaEventRecord");
  LOCALIZER_CUDA_RETURN_IF_ERROR(cudaMemcpyAsync(m.d_tasks.data(), m.h_tasks.data(),
                                                 sizeof(SrpSessionTask) * static_cast<size_t>(sessions),
                                                 cudaMemcpyHostToDevice, s),
                                 "cudaMemcpyAsync(SRP tasks)");
  LOCALIZER_CUDA_RETURN_IF_ERROR(cudaMemcpyAsync(m.d_spectra.data(), m.h_spectra.data(),
                                                 sizeof(float) * static_cast<size_t>(spectra_floats),
                                                 cudaMemcpyHostToDevice, s),
                                 "cudaMemcpyAsync(SRP spectra)");
  if (m.collect_timing) LOCALIZER_CUDA_RETURN_IF_ERROR(cudaEventRecord(m.events[1], s), "cudaEventRecord");
  SrpMapArgs map;
  map.arrays = m.d_arrays.data();
  map.tasks = m.d_tasks.data();
  map.spectra = m.d_spectra.data();
  map.directions = m.d_directions.data();
  map.lag_per_direction = m.d_lags.data();
  map.map = m.d_map.data();
  map.sessions = sessions;
  map.max_directions = m.max_directions;
  map.max_spectrum_floats = m.max_spectrum_floats;
  map.max_pairs = m.max_pairs;
  LOCALIZER_RETURN_IF_ERROR(LaunchSrpMap(map, s));
  SrpPeakArgs peak;
  peak.arrays = m.d_arrays.data();
  peak.tasks = m.d_tasks.data();
  peak.spectra = m.d_spectra.data();
  peak.directions = m.d_directions.data();
  peak.map = m.d_map.data();
  peak.results = m.d_results.data();
  peak.sessions = sessions;
  LOCALIZER_RETURN_IF_ERROR(LaunchSrpPeak(peak, s));
  if (m.collect_timing) LOCALIZER_CUDA_RETURN_IF_ERROR(cudaEventRecord(m.events[2], s), "cudaEventRecord");
  LOCALIZER_CUDA_RETURN_IF_ERROR(cudaMemcpyAsync(m.h_results.data(), m.d_results.data(),
                                                 sizeof(SrpSessionResult) * static_cast<size_t>(sessions),
                                                 cudaMemcpyDeviceToHost, s),
                                 "cudaMemcpyAsync(SRP results)");
  if (want_map) {
    LOCALIZER_CUDA_RETURN_IF_ERROR(cudaMemcpyAsync(m.h_map.data(), m.d_map.data(),
                                                   sizeof(float) * static_cast<size_t>(map_floats),
                                                   cudaMemcpyDeviceToHost, s),
                                   "cudaMemcpyAsync(SRP map)");
  }
  if (m.collect_timing) LOCALIZER_CUDA_RETURN_IF_ERROR(cudaEventRecord(m.events[3], s), "cudaEventRecord");
  LOCALIZER_RETURN_IF_ERROR(m.stream.Synchronize());
  if (m.collect_timing) {
    LOCALIZER_CUDA_RETURN_IF_ERROR(cudaEventElapsedTime(&m.last.total_ms, m.events[0], m.events[3]),
                                   "cudaEventElapsedTime");
    LOCALIZER_CUDA_RETURN_IF_ERROR(cudaEventElapsedTime(&m.last.kernels_ms, m.events[1], m.events[2]),
                                   "cudaEventElapsedTime");
  }
  for (size_t j = 0; j < jobs.size(); ++j) {
    const SrpJob& job = jobs[j];
    *job.out = DescribeSrpResult(m.arrays[static_cast<size_t>(job.array)], m.h_results.data()[j]);
    if (job.map_z != nullptr) {
      const SrpSessionTask& task = m.h_tasks.data()[j];
      const float* values = m.h_map.data() + task.map_offset;
      job.map_z->assign(values, values + m.directions[static_cast<size_t>(job.array)].size());
    }
  }
  return Status::Ok();
}

SrpBatch::Timing SrpBatch::last_timing() const { return impl_->last; }
int SrpBatch::max_sessions() const { return impl_->max_sessions; }
int SrpBatch::array_count() const { return static_cast<int>(impl_->arrays.size()); }
const SrpArrayModel& SrpBatch::array(int a) const { return impl_->arrays[static_cast<size_t>(a)]; }
const std::vector<engine::Vec3>& SrpBatch::directions(int a) const { return impl_->directions[static_cast<size_t>(a)]; }

}  // namespace localizer::gpu
