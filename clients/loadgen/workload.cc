#include "clients/loadgen/workload.h"

#include <algorithm>
#include <cmath>
#include <random>

#include "engine/core/block.h"
#include "engine/tdoa/fftw_util.h"
#include "wire/block_wire.h"

namespace localizer::loadgen {

namespace {

// loadtest.py's scene.
constexpr double kSoundSpeedMps = 1500.0;
constexpr double kArrayEdgeM = 1.5;
constexpr double kSourceM[3] = {2.5, 1.5, -1.0};
constexpr double kBandLowHz = 200.0;
constexpr double kBandHighHz = 8000.0;
constexpr double kSnrDb = 20.0;
constexpr double kAmplitude = 0.1;  // source std: keeps 16-bit PCM far from clipping

// Whole-sample TDOAs of kSourceM: arrival at each sensor minus at sensor 0.
std::vector<int> IntegerTdoas(const std::vector<double>& sensors_m, double sample_rate_hz) {
  const size_t count = sensors_m.size() / 3;
  std::vector<double> range_m(count);
  for (size_t k = 0; k < count; ++k) {
    const double dx = sensors_m[3 * k] - kSourceM[0], dy = sensors_m[3 * k + 1] - kSourceM[1],
                 dz = sensors_m[3 * k + 2] - kSourceM[2];
    range_m[k] = std::sqrt(dx * dx + dy * dy + dz * dz);
  }
  std::vector<int> tdoa(count);
  for (size_t k = 0; k < count; ++k) {
    tdoa[k] = static_cast<int>(std::lround((range_m[k] - range_m[0]) / kSoundSpeedMps * sample_rate_hz));
  }
  return tdoa;
}

// Band-limited white noise of std kAmplitude, periodic in n, as loadtest.py makes it: the
// spectrum of n white draws with the bins outside [kBandLowHz, band_high_hz] zeroed, back to
// time (a circular operation, so the result wraps seamlessly).
std::vector<double> PeriodicBroadband(int64_t n, double sample_rate_hz, double band_high_hz, std::mt19937_64& rng) {
  std::normal_distribution<double> normal;
  engine::FftwFloats time = engine::AllocateFftwFloats(static_cast<size_t>(n));
  engine::FftwFloats spectrum = engine::AllocateFftwFloats(2 * (static_cast<size_t>(n) / 2 + 1));
  for (int64_t i = 0; i < n; ++i) time[i] = static_cast<float>(normal(rng));
  {
    // The planner's mutex is taken inside (fftw_util.h).
    const engine::FftwPlan forward =
        engine::PlanRealForward(static_cast<int>(n), time.get(), spectrum.get(), FFTW_ESTIMATE);
    const engine::FftwPlan inverse =
        engine::PlanRealInverse(static_cast<int>(n), spectrum.get(), time.get(), FFTW_ESTIMATE);
    fftwf_execute(forward.get());
    for (int64_t k = 0; k <= n / 2; ++k) {
      const double f_hz = static_cast<double>(k) * sample_rate_hz / static_cast<double>(n);
      if (f_hz < kBandLowHz || f_hz > band_high_hz) spectrum[2 * k] = spectrum[2 * k + 1] = 0.0f;
    }
    fftwf_execute(inverse.get());  // c2r destroys its input: done with the spectrum
  }
  std::vector<double> source(time.get(), time.get() + n);
  double mean = 0.0, power = 0.0;
  for (double v : source) mean += v;
  mean /= static_cast<double>(n);
  for (double v : source) power += (v - mean) * (v - mean);
  const double scale = kAmplitude / std::sqrt(power / static_cast<double>(n));
  for (double& v : source) v *= scale;
  return source;
}

void PutVarint(uint64_t value, char* out, int* length) {
  while (value >= 0x80) {
    out[(*length)++] = static_cast<char>((value & 0x7F) | 0x80);
    value >>= 7;
  }
  out[(*length)++] = static_cast<char>(value);
}

int VarintBytes(uint64_t value) {
  int bytes = 1;
  while (value >= 0x80) {
    value >>= 7;
    ++bytes;
  }
  return bytes;
}

}  // namespace

std::vector<double> ArrayPositions(int channels, double edge_m) {
  const double a = edge_m / (2.0 * std::sqrt(2.0));
  std::vector<double> xyz = {a, a, a, a, -a, -a, -a, a, -a, -a, -a, a};
  const int extra = channels - 4;
  for (int k = 0; k < extra; ++k) {
    const double angle = 2.0 * M_PI * k / extra + 0.3;
    xyz.push_back(0.6 * edge_m * std::cos(angle));
    xyz.push_back(0.6 * edge_m * std::sin(angle));
    xyz.push_back(0.4 * edge_m * (k % 2 ? 1.0 : -1.0));
  }
  return xyz;
}

Workload::Workload(const LoadOptions& options) : options_(options) {
  sensors_m_ = ArrayPositions(options.channels, kArrayEdgeM);
  tdoa_samples_ = IntegerTdoas(sensors_m_, options.sample_rate_hz);
  band_high_hz_ = std::min(kBandHighHz, 0.45 * options.sample_rate_hz);

  const int64_t block = options.block_samples;
  const int64_t block_count = std::max<int64_t>(
      1, static_cast<int64_t>(std::ceil(options.signal_seconds * options.sample_rate_hz / static_cast<double>(block))));
  const int64_t n = block_count * block;
  std::mt19937_64 rng(static_cast<uint64_t>(options.seed));
  const std::vector<double> source = PeriodicBroadband(n, options.sample_rate_hz, band_high_hz_, rng);

  // Channel-major recording: channel k hears the source d_k samples late (d relative to the
  // earliest sensor), plus its own noise.
  const int channels = options.channels;
  const int earliest = *std::min_element(tdoa_samples_.begin(), tdoa_samples_.end());
  const double noise_std = kAmplitude * std::pow(10.0, -kSnrDb / 20.0);
  std::normal_distribution<double> normal;
  std::vector<float> recording(static_cast<size_t>(channels) * n);
  for (int k = 0; k < channels; ++k) {
    const int64_t delay = tdoa_samples_[k] - earliest;
    for (int64_t i = 0; i < n; ++i) {
      recording[k * n + i] = static_cast<float>(source[((i - delay) % n + n) % n] + noise_std * normal(rng));
    }
  }

  // One body per block: the block's channels cut out, encoded as the server will decode it.
  std::vector<float> chunk(static_cast<size_t>(channels) * block);
  v1::SampleBlock message;
  for (int64_t b = 0; b < block_count; ++b) {
    for (int k = 0; k < channels; ++k) {
      std::copy_n(recording.begin() + k * n + b * block, block, chunk.begin() + k * block);
    }
    engine::BlockView view;
    view.sequence = 0;
    view.channel_count = channels;
    view.samples_per_channel = block;
    view.samples = chunk.data();
    message.Clear();
    wire::EncodeBlock(view, options.pcm16, &message);
    message.set_sequence(0);  // not serialised: BlockPrefix writes the real one
    bodies_.push_back(message.SerializeAsString());
  }
}

std::string Workload::OpenRequest(int index) const {
  v1::TrackRequest request;
  v1::SessionConfig* config = request.mutable_open();
  v1::ArrayGeometry* array = config->mutable_array();
  for (size_t k = 0; k < sensors_m_.size() / 3; ++k) {
    v1::Vector3* p = array->add_sensors_m();
    p->set_x(sensors_m_[3 * k]);
    p->set_y(sensors_m_[3 * k + 1]);
    p->set_z(sensors_m_[3 * k + 2]);
  }
  array->set_sound_speed_mps(kSoundSpeedMps);
  array->set_reference_sensor(0);
  config->set_sample_rate_hz(options_.sample_rate_hz);
  config->set_frame_samples(static_cast<uint32_t>(options_.frame_samples));
  config->set_hop_samples(static_cast<uint32_t>(options_.hop_samples));
  config->mutable_filter()->set_particles(static_cast<uint32_t>(options_.particles));
  if (options_.motion == "one-std") {  // the wire's 0 is the default: off goes as -1
    v1::FilterConfig* filter = config->mutable_filter();
    filter->set_accel_level_floor(1.0);
    filter->set_accel_level_ceiling(1.0);
    filter->set_turn_rate_max_radps(-1.0);
    filter->set_speed_change_max_mps2(-1.0);
  }
  config->set_band_low_hz(kBandLowHz);
  config->set_band_high_hz(band_high_hz_);
  config->set_seed(static_cast<uint64_t>(options_.seed) + static_cast<uint64_t>(index));
  config->set_backend(options_.backend);
  config->set_label("loadgen-" + std::to_string(index));
  return request.SerializeAsString();
}

int Workload::BlockPrefix(uint64_t sequence, size_t body_bytes, char* out) {
  int length = 0;
  out[length++] = 0x1a;  // TrackRequest.block: field 3, length-delimited
  PutVarint(1 + VarintBytes(sequence) + body_bytes, out, &length);
  out[length++] = 0x08;  // SampleBlock.sequence: field 1, varint
  PutVarint(sequence, out, &length);
  return length;
}

}  // namespace localizer::loadgen
