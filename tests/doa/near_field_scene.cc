#include "tests/doa/near_field_scene.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>

#include "engine/core/measurement.h"
#include "engine/doa/pair_spectra.h"

namespace localizer::engine::testing {

std::vector<float> RenderNearFieldScene(const NearFieldScene& scene) {
  std::mt19937_64 rng(scene.seed);
  std::normal_distribution<double> gauss(0.0, 1.0);
  const auto samples = static_cast<int64_t>(scene.seconds * scene.sample_rate_hz);
  std::vector<RoomSource> sources;
  for (const Vec3& p : scene.sources_m) {
    RoomSource s;
    s.position_m = p;
    s.signal.resize(static_cast<size_t>(samples));
    for (double& v : s.signal) v = gauss(rng);
    sources.push_back(std::move(s));
  }
  auto rendered = RenderInRoom(scene.room, sources, scene.sensors_m, scene.sample_rate_hz, samples);
  if (!rendered.ok()) return {};
  std::vector<float> out = std::move(rendered).value();
  // The direct sound at 1 m has amplitude 1 / (4 pi) per unit of signal.
  const double noise_sd = 1.0 / (4.0 * std::numbers::pi) * std::pow(10.0, -scene.snr_db / 20.0);
  for (float& v : out) v += static_cast<float>(noise_sd * gauss(rng));
  return out;
}

std::vector<Estimate> StreamThrough(Session* session, const std::vector<float>& samples, int sensors) {
  const auto per_channel = static_cast<int64_t>(samples.size()) / sensors;
  std::vector<Estimate> out;
  constexpr int64_t kBlock = 4096;
  std::vector<float> block;
  uint64_t sequence = 1;
  for (int64_t start = 0; start + kBlock <= per_channel; start += kBlock) {
    block.clear();
    for (int m = 0; m < sensors; ++m) {
      const float* channel = samples.data() + m * per_channel + start;
      block.insert(block.end(), channel, channel + kBlock);
    }
    if (!session->Process(BlockView{sequence++, sensors, static_cast<int>(kBlock), block.data()}, &out).ok()) break;
  }
  return out;
}

std::vector<Vec3> LeastSquaresFixes(const std::vector<float>& samples, const std::vector<Vec3>& sensors_m,
                                    double sample_rate_hz, double sound_speed_mps, int frame_samples,
                                    int hop_samples, const Vec3& truth_m, const Vec3& plane_normal) {
  const int sensors = static_cast<int>(sensors_m.size());
  const auto per_channel = static_cast<int64_t>(samples.size()) / sensors;
  double aperture_m = 0.0;
  for (const Vec3& a : sensors_m) {
    for (const Vec3& b : sensors_m) aperture_m = std::max(aperture_m, (a - b).norm());
  }
  const double per_m = sample_rate_hz / sound_speed_mps;
  PairSpectraOptions options;
  options.sensors = sensors;
  options.frame_samples = frame_samples;
  options.sample_rate_hz = sample_rate_hz;
  options.max_lag_samples = static_cast<int>(std::ceil(aperture_m * per_m)) + 1;
  auto spectra = PairSpectra::Create(options);
  if (!spectra.ok()) return {};
  // The fix's free axes: the plane's two (normal given) or all three.
  Eigen::Matrix3d basis = Eigen::Matrix3d::Identity();
  int free = 3;
  if (plane_normal != Vec3::Zero()) {
    const Vec3 n = plane_normal.normalized();
    const Vec3 other = std::abs(n.x()) < 0.9 ? Vec3::UnitX() : Vec3::UnitY();
    basis.col(0) = n.cross(other).normalized();
    basis.col(1) = n.cross(basis.col(0));
    basis.col(2) = n;
    free = 2;
  }
  std::vector<Vec3> fixes;
  std::vector<float> frame(static_cast<size_t>(sensors) * frame_samples);
  Measurement field;
  for (int64_t start = 0; start + frame_samples <= per_channel; start += hop_samples) {
    for (int m = 0; m < sensors; ++m) {
      std::copy_n(samples.data() + m * per_channel + start, frame_samples,
                  frame.data() + static_cast<size_t>(m) * frame_samples);
    }
    if (!spectra->Analyse(frame.data(), &field).ok()) continue;
    std::vector<double> lag(static_cast<size_t>(spectra->pair_count()));
    for (int p = 0; p < spectra->pair_count(); ++p) {
      const std::vector<float>& gcc = field.pairs[static_cast<size_t>(p)].gcc;
      const auto best = std::max_element(gcc.begin(), gcc.end()) - gcc.begin();
      double l = static_cast<double>(best - options.max_lag_samples);
      for (int k = 0; k < 4; ++k) {  // Newton on the continuous GCC
        const PairSpectra::Value v = spectra->At(p, l);
        if (!(v.d2r < 0.0)) break;
        l -= std::clamp(v.dr / v.d2r, -0.5, 0.5);
      }
      lag[static_cast<size_t>(p)] = l;
    }
    Vec3 x_m = truth_m;
    for (int iteration = 0; iteration < 20; ++iteration) {
      Eigen::Matrix3d normal = Eigen::Matrix3d::Zero();
      Eigen::Vector3d rhs = Eigen::Vector3d::Zero();
      for (int p = 0; p < spectra->pair_count(); ++p) {
        const auto [i, j] = spectra->sensors_of(p);
        const Vec3 to_i = x_m - sensors_m[static_cast<size_t>(i)], to_j = x_m - sensors_m[static_cast<size_t>(j)];
        const double model = (to_i.norm() - to_j.norm()) * per_m;
        const Eigen::Vector3d g = basis.transpose() * (per_m * (to_i.normalized() - to_j.normalized()));
        normal += g * g.transpose();
        rhs += g * (lag[static_cast<size_t>(p)] - model);
      }
      if (free == 2) {
        normal.row(2).setZero();
        normal.col(2).setZero();
        normal(2, 2) = 1.0;
        rhs(2) = 0.0;
      }
      const Eigen::Vector3d step = normal.ldlt().solve(rhs);
      if (!step.allFinite()) break;
      x_m += basis * step;
      if (step.norm() < 1e-7) break;
    }
    fixes.push_back(x_m);
  }
  return fixes;
}

double Median(std::vector<double> values) {
  if (values.empty()) return std::nan("");
  const auto middle = values.begin() + static_cast<std::ptrdiff_t>(values.size() / 2);
  std::nth_element(values.begin(), middle, values.end());
  return *middle;
}

}  // namespace localizer::engine::testing
