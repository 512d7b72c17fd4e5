// The GPU SRP-PHAT's __host__ __device__ maths (gpu/srp/srp_math.cuh), run on the host and
// compared with engine/doa's CPU SrpPhat on the same frames. Compiled by nvcc, so the code under
// test is the code the kernels inline; it runs without a GPU.
//
// What is checked, on seeded plane waves (and noise alone) on the ReSpeaker board, a
// tetrahedron, a 7-microphone circle, an 8-microphone line and seeded random arrays:
//   - the spectra the tests hand the GPU are the engine's (tests/gpu/srp_test_scenes.h);
//   - the double lag sums equal PairSpectra's exact GCC and derivatives;
//   - the float map, as the map kernel computes it, equals SrpPhat::Statistic at every grid
//     direction within kSrpMapToleranceZ, and its arg-max is the CPU map's;
//   - the refinement from the float map's arg-max reaches the direction (within
//     kSrpDirectionToleranceRad) and statistic (kSrpStatisticToleranceRelative) the CPU's
//     Analyse reports, whether each pair's bins are summed whole or split over 32 lanes as a
//     warp splits them;
//   - the grid helpers and the array model (band, pairs, lags) match the CPU's construction.

// Eigen's CUDA support is for device code; this file uses Eigen on the host only.
#define EIGEN_NO_CUDA
// nvcc's front end flags engine/core/status.h's assignment of a [[nodiscard]] Status to a
// member as "ignoring return value" (g++ does not); the engine code is fine.
#pragma nv_diag_suppress 2810

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include "gpu/srp/srp_array.h"
#include "gpu/srp/srp_batch.h"
#include "gpu/srp/srp_grid.h"
#include "gpu/srp/srp_kernels.h"
#include "gpu/srp/srp_math.cuh"
#include "tests/gpu/srp_test_scenes.h"

namespace localizer::gpu {
namespace {

using engine::Vec3;
using testing::AngleRad;

struct NamedArray {
  std::string name;
  std::vector<Vec3> sensors;
};

std::vector<NamedArray> Arrays() {
  return {{"respeaker4", testing::Respeaker4()},
          {"tetra4", testing::Tetra4()},
          {"circle7", testing::Circle7()},
          {"line8", testing::Line8()},
          {"random5", testing::RandomArray(5, 0.12, 501)},
          {"random6", testing::RandomArray(6, 0.10, 602)}};
}

// Sums over all bins of a session's pair, as RefineDirection asks for them: in double from
// the spectra the device holds (float), in `lanes` lane-strided partial sums added in the order
// the warp's shuffle tree adds them (lanes = 1: one plain sum).
struct HostPairSums {
  const std::vector<float>* spectra;  // interleaved, P x B
  srp::SrpBand band;
  int lanes = 1;
  srp::LagSums operator()(int pair, double lag_samples) const {
    const float* g = spectra->data() + 2 * static_cast<size_t>(pair) * band.bins;
    std::vector<srp::LagSums> part(static_cast<size_t>(lanes));
    for (int lane = 0; lane < lanes; ++lane) part[static_cast<size_t>(lane)] = srp::PairLagSums(g, band, lag_samples, lane, lanes);
    for (int offset = lanes / 2; offset > 0; offset /= 2) {  // __shfl_down_sync's tree into lane 0
      for (int lane = 0; lane + offset < lanes; ++lane) {
        part[static_cast<size_t>(lane)].r += part[static_cast<size_t>(lane + offset)].r;
        part[static_cast<size_t>(lane)].dr += part[static_cast<size_t>(lane + offset)].dr;
        part[static_cast<size_t>(lane)].d2r += part[static_cast<size_t>(lane + offset)].d2r;
      }
    }
    return part[0];
  }
};

// One analysed frame: the CPU analyser after Analyse, its peak, the model, the spectra.
struct Frame {
  engine::SrpPhat cpu;
  std::vector<engine::DirectionPeak> peaks;
  SrpArrayModel model;
  std::vector<std::complex<double>> spectra;
  std::vector<float> spectra_float;  // interleaved, as the device gets them
  std::vector<float> lags_float;     // D_p as the map kernel reads them
};

Frame Analysed(const std::vector<Vec3>& sensors, const Vec3& direction, double snr, uint64_t seed,
               int frame_samples = 256) {
  const engine::SrpOptions o = testing::FrameOptions(frame_samples);
  StatusOr<engine::SrpPhat> cpu = engine::SrpPhat::Create(sensors, o);
  EXPECT_TRUE(cpu.ok()) << cpu.status().ToString();
  StatusOr<SrpArrayModel> model = MakeSrpArrayModel(sensors, o);
  EXPECT_TRUE(model.ok()) << model.status().ToString();
  const std::vector<float> samples = testing::PlaneWave(sensors, o, direction, snr, seed);
  StatusOr<std::vector<engine::DirectionPeak>> peaks = cpu->Analyse(samples.data());
  EXPECT_TRUE(peaks.ok()) << peaks.status().ToString();
  Frame f{std::move(*cpu), std::move(*peaks), std::move(*model), {}, {}, {}};
  f.spectra = testing::RecoveredSpectra(f.cpu, f.model);
  for (const std::complex<float>& v : testing::AsFloat(f.spectra)) {
    f.spectra_float.push_back(v.real());
    f.spectra_float.push_back(v.imag());
  }
  for (double d : f.model.lag_per_direction) f.lags_float.push_back(static_cast<float>(d));
  return f;
}

Vec3 RandomDirection(std::mt19937_64& rng) {
  std::normal_distribution<double> n(0.0, 1.0);
  return Vec3(n(rng), n(rng), n(rng)).normalized();
}

// The float map as SrpMapKernel writes it.
std::vector<float> FloatMap(const Frame& f, const std::vector<Vec3>& grid) {
  std::vector<float> map;
  for (const Vec3& u : grid) {
    const float power = srp::SteeredPower<float>(f.spectra_float.data(), f.lags_float.data(), f.model.pairs, f.model.band,
                                                 static_cast<float>(u.x()), static_cast<float>(u.y()),
                                                 static_cast<float>(u.z()));
    map.push_back(power * static_cast<float>(f.model.z_per_power));
  }
  return map;
}

srp::RefineCell StartCell(const SrpArrayModel& model, const Vec3& u) {
  srp::RefineCell cell;
  cell.u = {u.x(), u.y(), u.z()};
  cell.theta_rad = std::acos(std::clamp(u.dot(model.shape.axis), -1.0, 1.0));
  return cell;
}

// ---- The inputs ------------------------------------------------------------------------------

TEST(SrpMath, ArrayModelIsTheCpusConstruction) {
  for (const NamedArray& a : Arrays()) {
    StatusOr<SrpArrayModel> model = MakeSrpArrayModel(a.sensors, testing::FrameOptions());
    ASSERT_TRUE(model.ok()) << a.name << ": " << model.status().ToString();
    const int n = static_cast<int>(a.sensors.size());
    EXPECT_EQ(model->pairs, n * (n - 1) / 2) << a.name;
    // 100-7000 Hz of an M-point transform at 16 kHz: bins ceil(100 M / 16000) .. floor(7000 M / 16000).
    const int m = model->fft_size;
    EXPECT_EQ(model->band.first_bin, static_cast<int>(std::ceil(100.0 * m / 16000.0))) << a.name;
    EXPECT_EQ(model->band.first_bin + model->band.bins - 1, static_cast<int>(std::floor(7000.0 * m / 16000.0)))
        << a.name;
    EXPECT_GT(model->threshold, 3.0) << a.name;
  }
  StatusOr<SrpArrayModel> respeaker = MakeSrpArrayModel(testing::Respeaker4(), testing::FrameOptions());
  ASSERT_TRUE(respeaker.ok());
  std::printf("respeaker4, 256 at 16 kHz, 100-7000 Hz: M = %d, first bin %d, B = %d, P = %d\n", respeaker->fft_size,
              respeaker->band.first_bin, respeaker->band.bins, respeaker->pairs);
  engine::SrpOptions bad = testing::FrameOptions();
  bad.sample_rate_hz = -1.0;
  EXPECT_EQ(MakeSrpArrayModel(testing::Respeaker4(), bad).status().code(), StatusCode::kInvalidArgument);
  EXPECT_EQ(MakeSrpArrayModel({Vec3::Zero()}, testing::FrameOptions()).status().code(),
            StatusCode::kInvalidArgument);
}

TEST(SrpMath, RecoveredSpectraAreUnitPhasorsAndGiveTheEnginesGcc) {
  std::mt19937_64 rng(7);
  for (const NamedArray& a : Arrays()) {
    const Frame f = Analysed(a.sensors, RandomDirection(rng), 3.0, 1234);
    double worst_magnitude = 0.0, worst_r = 0.0, worst_dr = 0.0, worst_d2r = 0.0;
    for (const std::complex<double>& g : f.spectra) worst_magnitude = std::max(worst_magnitude, std::abs(std::abs(g) - 1.0));
    std::uniform_real_distribution<double> lag(-6.0, 6.0);
    for (int p = 0; p < f.model.pairs; ++p) {
      // Double spectra through the double lag sums (the refinement's maths) against PairSpectra.
      std::vector<double> interleaved;
      for (int b = 0; b < f.model.band.bins; ++b) {
        const std::complex<double> g = f.spectra[static_cast<size_t>(p) * f.model.band.bins + b];
        interleaved.push_back(g.real());
        interleaved.push_back(g.imag());
      }
      for (int trial = 0; trial < 20; ++trial) {
        const double l = lag(rng);
        const engine::PairSpectra::Value cpu = f.cpu.spectra().WholeValueAt(p, l);
        // PairLagSums reads floats; the double path is checked by summing the same formula here.
        double r = 0.0, dr = 0.0, d2r = 0.0;
        for (int b = 0; b < f.model.band.bins; ++b) {
          const double w = f.model.band.radians_per_bin_lag * (f.model.band.first_bin + b);
          const std::complex<double> t = std::complex<double>(interleaved[2 * b], interleaved[2 * b + 1]) *
                                         std::exp(std::complex<double>(0.0, w * l));
          r += t.real();
          dr -= w * t.imag();
          d2r -= w * w * t.real();
        }
        const double inv_b = f.model.Geometry().inv_bins;
        worst_r = std::max(worst_r, std::abs(r * inv_b - cpu.r));
        worst_dr = std::max(worst_dr, std::abs(dr * inv_b - cpu.dr));
        worst_d2r = std::max(worst_d2r, std::abs(d2r * inv_b - cpu.d2r));
        // And PairLagSums on the float spectra: float rounding of G only (~6e-8 per bin).
        const srp::LagSums s =
            srp::PairLagSums(f.spectra_float.data() + 2 * static_cast<size_t>(p) * f.model.band.bins, f.model.band, l, 0, 1);
        EXPECT_NEAR(s.r * inv_b, cpu.r, 1e-6) << a.name;
        EXPECT_NEAR(s.dr * inv_b, cpu.dr, 1e-6) << a.name;
        EXPECT_NEAR(s.d2r * inv_b, cpu.d2r, 1e-5) << a.name;
      }
    }
    // |G| = 1 wherever both channels are heard (plane waves: every bin).
    EXPECT_LT(worst_magnitude, 1e-9) << a.name;
    EXPECT_LT(worst_r, 1e-12) << a.name;
    EXPECT_LT(worst_dr, 1e-11) << a.name;
    EXPECT_LT(worst_d2r, 1e-10) << a.name;
  }
}

// ---- The map -----------------------------------------------------------------------------------

TEST(SrpMath, FloatMapEqualsCpuStatisticAndHasTheCpusArgMax) {
  std::mt19937_64 rng(21);
  double worst = 0.0;
  int frames = 0, same_index = 0;
  // Frames of 256 on every array, and of 1024 (about 450 bins: longer sums) on the line and a cube
  // of 8.
  std::vector<std::pair<NamedArray, int>> cases;
  for (const NamedArray& a : Arrays()) cases.emplace_back(a, 256);
  cases.emplace_back(NamedArray{"line8/1024", testing::Line8()}, 1024);
  cases.emplace_back(NamedArray{"random8/1024", testing::RandomArray(8, 0.1, 88)}, 1024);
  for (const auto& [a, frame_samples] : cases) {
    for (int trial = 0; trial < 4; ++trial) {
      const double snr = trial == 3 ? 0.0 : 0.3 * (trial + 1);  // the last: noise alone
      const Frame f = Analysed(a.sensors, RandomDirection(rng), snr, 100 * trial + 17, frame_samples);
      const std::vector<Vec3> grid = CpuLikeGrid(f.model);
      const std::vector<float> map = FloatMap(f, grid);
      std::vector<double> cpu;
      double frame_worst = 0.0;
      for (size_t d = 0; d < grid.size(); ++d) {
        cpu.push_back(f.cpu.Statistic(grid[d]));
        frame_worst = std::max(frame_worst, std::abs(static_cast<double>(map[d]) - cpu.back()));
      }
      EXPECT_LE(frame_worst, kSrpMapToleranceZ) << a.name << " trial " << trial;
      worst = std::max(worst, frame_worst);
      // The arg-max: the same direction, or one whose CPU value is within the tolerance of it.
      const size_t gpu_best = static_cast<size_t>(std::max_element(map.begin(), map.end()) - map.begin());
      const size_t cpu_best = static_cast<size_t>(std::max_element(cpu.begin(), cpu.end()) - cpu.begin());
      ++frames;
      if (gpu_best == cpu_best) ++same_index;
      EXPECT_LE(cpu[cpu_best] - cpu[gpu_best], 2.0 * kSrpMapToleranceZ) << a.name << " trial " << trial;
    }
  }
  std::printf("float map vs SrpPhat::Statistic: max |dz| = %.3g over %d frames (tolerance %.1g); "
              "arg-max index equal in %d of %d\n",
              worst, frames, kSrpMapToleranceZ, same_index, frames);
}

TEST(SrpMath, DoubleMapEqualsCpuStatisticToRounding) {
  std::mt19937_64 rng(33);
  for (const NamedArray& a : Arrays()) {
    const Frame f = Analysed(a.sensors, RandomDirection(rng), 1.0, 77);
    std::vector<double> lags = f.model.lag_per_direction;
    std::vector<float> lag_floats(lags.begin(), lags.end());
    const std::vector<Vec3> grid = CpuLikeGrid(f.model);
    double worst = 0.0;
    for (size_t d = 0; d < grid.size(); d += 7) {
      // Double arithmetic over the float spectra and float lags: what is left is their rounding.
      const double power = srp::SteeredPower<double>(f.spectra_float.data(), lag_floats.data(), f.model.pairs,
                                                     f.model.band, grid[d].x(), grid[d].y(), grid[d].z());
      worst = std::max(worst, std::abs(power * f.model.z_per_power - f.cpu.Statistic(grid[d])));
    }
    EXPECT_LT(worst, 2e-5) << a.name;
  }
}

TEST(SrpMath, LaneSplitSumsEqualWholeSums) {
  const Frame f = Analysed(testing::Circle7(), Vec3(0.3, -0.5, 0.81).normalized(), 1.0, 5);
  std::mt19937_64 rng(9);
  std::uniform_real_distribution<double> lag(-5.0, 5.0);
  for (int p = 0; p < f.model.pairs; ++p) {
    const float* g = f.spectra_float.data() + 2 * static_cast<size_t>(p) * f.model.band.bins;
    for (int trial = 0; trial < 10; ++trial) {
      const double l = lag(rng);
      const float whole = srp::SteeredPairSum<float>(g, f.model.band, static_cast<float>(l), 0, 1);
      float split = 0.0f;
      double split_double = 0.0;
      for (int lane = 0; lane < 32; ++lane) {
        split += srp::SteeredPairSum<float>(g, f.model.band, static_cast<float>(l), lane, 32);
        split_double += srp::PairLagSums(g, f.model.band, l, lane, 32).r;
      }
      const double exact = srp::PairLagSums(g, f.model.band, l, 0, 1).r;
      EXPECT_NEAR(whole, exact, 2e-4);
      EXPECT_NEAR(split, exact, 2e-4);
      EXPECT_NEAR(split_double, exact, 1e-11);
    }
  }
}

// ---- The peak ------------------------------------------------------------------------------------

// The CPU reports a planar array's direction on the normal's side (no source_side); the
// refinement may end on either side: compare with the mirror folded.
double DirectionError(const SrpArrayModel& model, const srp::RefineResult& r, const engine::DirectionPeak& cpu) {
  if (model.shape.shape == engine::ArrayShape::kLinear) return std::abs(r.cell.theta_rad - cpu.cone_angle_rad);
  Vec3 u(r.cell.u.x, r.cell.u.y, r.cell.u.z);
  if (model.shape.shape == engine::ArrayShape::kPlanar && u.dot(model.shape.axis) < 0.0)
    u -= 2.0 * u.dot(model.shape.axis) * model.shape.axis;
  return AngleRad(u, cpu.direction);
}

TEST(SrpMath, RefinementReachesTheCpusPeak) {
  std::mt19937_64 rng(44);
  double worst_rad = 0.0, worst_z = 0.0, worst_lanes_rad = 0.0;
  int compared = 0, probes = 0, most_probes = 0;
  // Frames of 256 on every array, and of 1024 on the line and an 8-microphone cube (the
  // device test's opt-in shared-memory case).
  std::vector<std::pair<NamedArray, int>> cases;
  for (const NamedArray& a : Arrays()) cases.emplace_back(a, 256);
  cases.emplace_back(NamedArray{"line8/1024", testing::Line8()}, 1024);
  cases.emplace_back(NamedArray{"random8/1024", testing::RandomArray(8, 0.1, 88)}, 1024);
  for (const auto& [a, frame_samples] : cases) {
    for (int trial = 0; trial < 5; ++trial) {
      const Frame f = Analysed(a.sensors, RandomDirection(rng), 0.5 + trial, 900 + trial, frame_samples);
      ASSERT_EQ(f.peaks.size(), 1u) << a.name << " trial " << trial << ": the CPU found no source";
      const std::vector<Vec3> grid = CpuLikeGrid(f.model);
      const std::vector<float> map = FloatMap(f, grid);
      const size_t best = static_cast<size_t>(std::max_element(map.begin(), map.end()) - map.begin());
      const srp::RefineGeometry geo = f.model.Geometry();
      HostPairSums whole{&f.spectra_float, f.model.band, 1};
      const srp::RefineResult r = srp::RefineDirection(geo, StartCell(f.model, grid[best]), whole);
      const double z = r.value / (f.model.noise_sigma * std::sqrt(static_cast<double>(f.model.pairs)));
      const double error = DirectionError(f.model, r, f.peaks[0]);
      EXPECT_LT(error, kSrpDirectionToleranceRad) << a.name << " trial " << trial;
      EXPECT_NEAR(z, f.peaks[0].statistic, kSrpStatisticToleranceRelative * f.peaks[0].statistic)
          << a.name << " trial " << trial;
      worst_rad = std::max(worst_rad, error);
      worst_z = std::max(worst_z, std::abs(z - f.peaks[0].statistic) / f.peaks[0].statistic);
      // The warp's split (32 lanes, shuffle-tree order): the same path to rounding.
      HostPairSums lanes{&f.spectra_float, f.model.band, 32};
      const srp::RefineResult split = srp::RefineDirection(geo, StartCell(f.model, grid[best]), lanes);
      const double split_rad =
          f.model.shape.shape == engine::ArrayShape::kLinear
              ? std::abs(split.cell.theta_rad - r.cell.theta_rad)
              : AngleRad(Vec3(split.cell.u.x, split.cell.u.y, split.cell.u.z), Vec3(r.cell.u.x, r.cell.u.y, r.cell.u.z));
      EXPECT_LE(split_rad, kSrpDirectionToleranceRad) << a.name << " trial " << trial;
      worst_lanes_rad = std::max(worst_lanes_rad, split_rad);
      ++compared;
      probes += r.probes;
      most_probes = std::max(most_probes, r.probes);
    }
  }
  std::printf("refined from the float map's arg-max vs the CPU's Analyse: max angle %.3g rad, max relative z %.3g "
              "over %d frames; 32-lane split vs whole sums: max %.3g rad; probes per refinement: mean %.1f, max %d\n",
              worst_rad, worst_z, compared, worst_lanes_rad, static_cast<double>(probes) / compared, most_probes);
}

// SrpPeakKernel's path on the host: the grid stored in float, the first maximum of the float
// map by BetterMapPeak, the start cell, the refinement split over 32 lanes, then the batch's
// description of the result: what Run reports equals the CPU's DirectionPeak (direction or
// cone angle, mirror candidate, statistic, threshold), planar arrays with and without a
// source side.
TEST(SrpMath, PeakKernelPathDescribesTheCpusPeak) {
  std::mt19937_64 rng(55);
  struct Case {
    NamedArray array;
    Vec3 source_side;
  };
  const std::vector<Case> cases = {{Arrays()[0], Vec3::Zero()},     {Arrays()[0], Vec3(0.1, 0.0, -1.0)},
                                   {Arrays()[1], Vec3::Zero()},     {Arrays()[2], Vec3(0.0, 0.3, 1.0)},
                                   {Arrays()[3], Vec3::Zero()},     {Arrays()[5], Vec3::Zero()}};
  for (const Case& c : cases) {
    for (int trial = 0; trial < 3; ++trial) {
      engine::SrpOptions o = testing::FrameOptions();
      o.source_side = c.source_side;
      StatusOr<engine::SrpPhat> cpu = engine::SrpPhat::Create(c.array.sensors, o);
      StatusOr<SrpArrayModel> model = MakeSrpArrayModel(c.array.sensors, o);
      ASSERT_TRUE(cpu.ok() && model.ok());
      const std::vector<float> samples = testing::PlaneWave(c.array.sensors, o, RandomDirection(rng), 2.0, 40 + trial);
      StatusOr<std::vector<engine::DirectionPeak>> want = cpu->Analyse(samples.data());
      ASSERT_TRUE(want.ok() && want->size() == 1u) << c.array.name;
      std::vector<float> g, lags, grid;
      for (const std::complex<float>& v : testing::AsFloat(testing::RecoveredSpectra(*cpu, *model))) {
        g.push_back(v.real());
        g.push_back(v.imag());
      }
      for (double d : model->lag_per_direction) lags.push_back(static_cast<float>(d));
      for (const Vec3& u : CpuLikeGrid(*model))
        grid.insert(grid.end(), {static_cast<float>(u.x()), static_cast<float>(u.y()), static_cast<float>(u.z())});
      const int directions = static_cast<int>(grid.size() / 3);
      srp::MapPeak best = srp::NoMapPeak();
      for (int d = 0; d < directions; ++d) {
        const float* u = grid.data() + 3 * d;
        const float z = srp::SteeredPower<float>(g.data(), lags.data(), model->pairs, model->band, u[0], u[1], u[2]) *
                        static_cast<float>(model->z_per_power);
        best = srp::BetterMapPeak(best, {z, d});
      }
      const srp::RefineGeometry geo = model->Geometry();
      HostPairSums lanes{&g, model->band, 32};
      const srp::RefineResult r =
          srp::RefineDirection(geo, srp::StartCell(grid.data() + 3 * best.index, geo.axis), lanes);
      SrpSessionResult result;
      result.grid_index = best.index;
      result.grid_z = best.value;
      result.ux = r.cell.u.x;
      result.uy = r.cell.u.y;
      result.uz = r.cell.u.z;
      result.theta_rad = r.cell.theta_rad;
      result.z = r.value * model->band.bins * model->z_per_power;
      result.iterations = r.iterations;
      const SrpPeak got = DescribeSrpResult(*model, result);
      const engine::DirectionPeak& w = (*want)[0];
      const std::string where = c.array.name + " trial " + std::to_string(trial);
      EXPECT_NEAR(got.statistic, w.statistic, kSrpStatisticToleranceRelative * w.statistic) << where;
      EXPECT_EQ(got.threshold, w.threshold) << where;
      EXPECT_EQ(got.mirror_ambiguous, w.mirror_ambiguous) << where;
      if (model->shape.shape == engine::ArrayShape::kLinear) {
        EXPECT_NEAR(got.cone_angle_rad, w.cone_angle_rad, kSrpDirectionToleranceRad) << where;
        EXPECT_TRUE(std::isnan(got.direction.x())) << where;
        continue;
      }
      EXPECT_LT(AngleRad(got.direction, w.direction), kSrpDirectionToleranceRad) << where;
      if (w.mirror_ambiguous) EXPECT_LT(AngleRad(got.mirror_direction, w.mirror_direction), kSrpDirectionToleranceRad) << where;
      if (c.source_side.norm() > 0.0) EXPECT_GT(got.direction.dot(c.source_side), 0.0) << where;
    }
  }
}

TEST(SrpMath, MapPeakOrderIsTotal) {
  const srp::MapPeak a{1.0f, 5}, b{1.0f, 3}, c{2.0f, 9};
  EXPECT_EQ(srp::BetterMapPeak(a, b).index, 3);
  EXPECT_EQ(srp::BetterMapPeak(b, a).index, 3);
  EXPECT_EQ(srp::BetterMapPeak(a, c).index, 9);
  EXPECT_EQ(srp::BetterMapPeak(srp::NoMapPeak(), a).index, 5);
  // NaN never wins: a map of NaN leaves the index past the grid (the kernel reports -1).
  const srp::MapPeak nan{std::nanf(""), 0};
  EXPECT_EQ(srp::BetterMapPeak(srp::NoMapPeak(), nan).index, srp::NoMapPeak().index);
  EXPECT_EQ(srp::BetterMapPeak(nan, srp::NoMapPeak()).index, srp::NoMapPeak().index);
  EXPECT_EQ(srp::BetterMapPeak(nan, a).index, 5);
  EXPECT_EQ(srp::BetterMapPeak(a, nan).index, 5);
}

// ---- Grids ---------------------------------------------------------------------------------------

TEST(SrpGrid, FibonacciDirectionsAreUnitAndSpread) {
  const std::vector<Vec3> grid = FibonacciDirections(2562);
  ASSERT_EQ(grid.size(), 2562u);
  Vec3 mean = Vec3::Zero();
  for (const Vec3& u : grid) {
    EXPECT_NEAR(u.norm(), 1.0, 1e-12);
    mean += u / 2562.0;
  }
  EXPECT_LT(mean.norm(), 1e-3);
}

TEST(SrpGrid, CpuLikeGridCoversWhatTheCpuSearches) {
  StatusOr<SrpArrayModel> planar = MakeSrpArrayModel(testing::Respeaker4(), testing::FrameOptions());
  StatusOr<SrpArrayModel> volumetric = MakeSrpArrayModel(testing::Tetra4(), testing::FrameOptions());
  StatusOr<SrpArrayModel> linear = MakeSrpArrayModel(testing::Line8(), testing::FrameOptions());
  ASSERT_TRUE(planar.ok() && volumetric.ok() && linear.ok());
  const std::vector<Vec3> p = CpuLikeGrid(*planar), v = CpuLikeGrid(*volumetric), l = CpuLikeGrid(*linear);
  std::printf("CPU-like grids at 16 kHz: respeaker4 %zu (hemisphere), tetra4 %zu, line8 %zu\n", p.size(), v.size(),
              l.size());
  for (const Vec3& u : p) EXPECT_GT(u.dot(planar->shape.axis), -0.2);
  EXPECT_GE(v.size(), 128u);
  for (const Vec3& u : l) EXPECT_NEAR(u.norm(), 1.0, 1e-12);
  // Linear: arcs of cone angle in (0, pi), increasing.
  for (size_t i = 1; i < l.size(); ++i) EXPECT_LT(l[i].dot(linear->shape.axis), l[i - 1].dot(linear->shape.axis));
}

}  // namespace
}  // namespace localizer::gpu
