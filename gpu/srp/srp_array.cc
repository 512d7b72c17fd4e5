#include "gpu/srp/srp_array.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>

namespace localizer::gpu {

srp::RefineGeometry SrpArrayModel::Geometry() const {
  srp::RefineGeometry g;
  switch (shape.shape) {
    case engine::ArrayShape::kLinear:
      g.shape = srp::kLinear;
      break;
    case engine::ArrayShape::kPlanar:
      g.shape = srp::kPlanar;
      break;
    case engine::ArrayShape::kVolumetric:
      g.shape = srp::kVolumetric;
      break;
  }
  g.pairs = pairs;
  g.axis = {shape.axis.x(), shape.axis.y(), shape.axis.z()};
  g.max_step_rad = 1.0 / max_spread;  // the CPU's 2 x leaf radius, leaf radius = 0.5 / max spread
  g.inv_bins = 1.0 / band.bins;
  g.lag_per_direction = lag_per_direction.data();
  return g;
}

StatusOr<SrpArrayModel> MakeSrpArrayModel(const std::vector<engine::Vec3>& sensors_m,
                                          const engine::SrpOptions& options) {
  StatusOr<engine::SrpPhat> cpu = engine::SrpPhat::Create(sensors_m, options);
  if (!cpu.ok()) return cpu.status();
  SrpArrayModel m;
  m.shape = cpu->shape();
  m.sensors = static_cast<int>(sensors_m.size());
  m.pairs = cpu->pair_count();
  m.fft_size = cpu->spectra().fft_size();
  m.noise_sigma = cpu->spectra().noise_sigma();
  m.threshold = cpu->threshold();
  m.source_side = options.source_side;
  // PairSpectra's band: bins 1 .. M/2 - 1 whose frequency lies in [low, high] (consecutive).
  const double high_hz = options.band_high_hz > 0.0 ? options.band_high_hz : 0.5 * options.sample_rate_hz;
  int first = -1, count = 0;
  for (int k = 1; k < m.fft_size / 2; ++k) {
    const double f_hz = k * options.sample_rate_hz / m.fft_size;
    if (f_hz >= options.band_low_hz && f_hz <= high_hz) {
      if (first < 0) first = k;
      ++count;
    }
  }
  if (first < 0 || count != cpu->spectra().band_bins()) {
    return Internal("the SRP band's bins (" + std::to_string(count) + ") differ from the CPU's (" +
                    std::to_string(cpu->spectra().band_bins()) + ")");
  }
  m.band.first_bin = first;
  m.band.bins = count;
  m.band.radians_per_bin_lag = 2.0 * std::numbers::pi / m.fft_size;
  const double per_m = options.sample_rate_hz / options.sound_speed_mps;
  const bool linear = m.shape.shape == engine::ArrayShape::kLinear;
  for (int p = 0; p < m.pairs; ++p) {
    const auto [i, j] = cpu->spectra().sensors_of(p);
    const engine::Vec3 d = -(sensors_m[static_cast<size_t>(i)] - sensors_m[static_cast<size_t>(j)]) * per_m;
    m.lag_per_direction.insert(m.lag_per_direction.end(), {d.x(), d.y(), d.z()});
    m.max_spread = std::max(m.max_spread, linear ? std::abs(d.dot(m.shape.axis)) : d.norm());
  }
  m.z_per_power = 1.0 / (m.band.bins * m.noise_sigma * std::sqrt(static_cast<double>(m.pairs)));
  return m;
}

}  // namespace localizer::gpu
