// A host model of one particle-bank session: the kernel sequence of gpu/filters/pf_kernels.h
// written as plain loops over the same descriptor (pf::FillSessionStep) and the same
// per-particle maths (gpu/filters/pf_math.cuh). It differs from the device only where the
// device's results are not meant to be reproduced bit for bit: sums run sequentially in
// double (the device: float per block of 256, then double per session) and normals come
// from the engine's counter hash and Box-Muller (engine/core/fast_math.h; the device:
// Philox). Tests use it to show, without a GPU, that the
// GPU algorithm tracks as the CPU filter does; with a GPU, particle_bank_test.cc checks the
// kernels themselves.
#pragma once

#include <cmath>
#include <cstdint>
#include <utility>
#include <vector>

#include "engine/array/array_geometry.h"
#include "engine/core/fast_math.h"
#include "engine/filters/particle_filter.h"
#include "engine/filters/tracker.h"
#include "gpu/filters/pf_kernels.h"
#include "gpu/filters/pf_math.cuh"
#include "gpu/filters/step_builder.h"

namespace localizer::gpu::testing {

class HostBankModel {
 public:
  HostBankModel(const engine::ArrayGeometry& array, const engine::ParticleFilterOptions& options)
      : config_(std::move(pf::MakeSessionConfig(array, options)).value()), n_(options.particles), seed_(options.seed) {
    for (int c = 0; c < 6; ++c) {
      x_[c].assign(static_cast<size_t>(n_), 0.0f);
      next_[c].assign(static_cast<size_t>(n_), 0.0f);
    }
    SetEqualWeights();
  }

  void InitialiseGaussian(const engine::Vec6& mean, const engine::Mat6& root) {
    Normals(6 * n_);
    for (int i = 0; i < n_; ++i) {
      const float* z = &normals_[6 * static_cast<size_t>(i)];
      for (int r = 0; r < 6; ++r) {
        float v = static_cast<float>(mean(r) - (r < 3 ? config_.origin_m[r] : 0.0));
        for (int k = 0; k < 6; ++k) v += static_cast<float>(root(r, k)) * z[k];
        x_[r][static_cast<size_t>(i)] = v;
      }
    }
    SetEqualWeights();
    ess_ = n_;
  }

  // One Step of the bank for this session; returns the device-shaped output.
  Status Step(double dt_s, const engine::Measurement* m, const int* used, const double* sigmas_s, pf::StepOutput* out) {
    pf::SessionStep s{};
    std::vector<float> gcc;
    LOCALIZER_RETURN_IF_ERROR(pf::FillSessionStep(config_, {dt_s, m, used, sigmas_s}, &gcc, &s));
    *out = pf::StepOutput{};
    if (s.do_predict) {
      Normals(3 * n_);
      for (size_t i = 0; i < static_cast<size_t>(n_); ++i) {
        float p[6];
        Load(i, p);
        const float* a = &normals_[3 * i];
        pf::PredictParticle(p, s.dt, s.a_to_p, s.a_to_v, a[0], a[1], a[2]);
        Store(i, p);
      }
    }
    bool resample = false;
    out->ess = ess_;
    if (s.do_update) {
      for (size_t i = 0; i < static_cast<size_t>(n_); ++i) {
        float p[6];
        Load(i, p);
        const pf::RangeRate ref = pf::RangeAndRate(p, s.reference[0], s.reference[1], s.reference[2]);
        float ll = 0.0f;
        for (int k = 0; k < s.pairs; ++k) {
          const pf::PairParams& pp = s.pair[k];
          if (!pp.used) continue;
          const float h = pf::PairDelay(pf::RangeAndRate(p, pp.sensor[0], pp.sensor[1], pp.sensor[2]), ref,
                                        pp.half_delay_s, s.inv_c);
          const float e = (pp.delay_s - h) * pp.inv_sigma;
          ll += pp.gcc_offset >= 0
                    ? pp.gcc_gain * engine::CatmullRomRead(gcc.data() + pp.gcc_offset,
                                                           engine::GccFineLag(h, pp.lag_scale, pp.lag0), pp.last_lag)
                    : pf::StudentTLogLikelihood(e, s.inv_dof, s.half_dof_plus_1);
          out->sum_e[k] += w_[i] * e;
          out->sum_e2[k] += w_[i] * e * e;
        }
        logw_[i] += ll;
      }
      float max_logw = -INFINITY;
      for (float v : logw_) max_logw = std::fmax(max_logw, v);
      double sum = 0.0, sum_sq = 0.0;
      for (float v : logw_) {
        const double u = std::exp(static_cast<double>(v - max_logw));
        sum += u;
        sum_sq += u * u;
      }
      out->ess = ess_ = sum * sum / sum_sq;
      const float inv_sum = static_cast<float>(1.0 / sum), log_norm = static_cast<float>(max_logw + std::log(sum));
      for (size_t i = 0; i < static_cast<size_t>(n_); ++i) {
        w_[i] = std::exp(logw_[i] - max_logw) * inv_sum;
        logw_[i] -= log_norm;
      }
      resample = out->ess < s.resample_below;
    }
    // Moments about particle 0.
    float shift[6];
    Load(0, shift);
    double sums[pf::kMomentSums] = {};
    for (size_t i = 0; i < static_cast<size_t>(n_); ++i) {
      float p[6], terms[pf::kMomentSums];
      Load(i, p);
      pf::MomentTerms(p, shift, w_[i], terms);
      for (int k = 0; k < pf::kMomentSums; ++k) sums[k] += terms[k];
    }
    pf::FinishMoments(sums, shift, out->mean, out->cov);
    if (!resample) return Status::Ok();
    out->resampled = 1;
    std::vector<double> cumulative(static_cast<size_t>(n_));
    double acc = 0.0;
    for (size_t i = 0; i < cumulative.size(); ++i) cumulative[i] = acc += w_[i];
    const double u0 = 1.0f - engine::UniformFromCounter(NextKey(), 0);
    float a = 1.0f, lw_shift[6] = {}, root[21] = {};
    if (s.kernel) {
      double l[36];
      out->cholesky_fallback = pf::CholeskyLower6(out->cov, l) ? 0 : 1;
      a = static_cast<float>(s.kernel_a);
      int k = 0;
      for (int r = 0; r < 6; ++r) {
        lw_shift[r] = static_cast<float>((1.0 - s.kernel_a) * out->mean[r]);
        for (int c = 0; c <= r; ++c) root[k++] = static_cast<float>(s.kernel_h * l[r * 6 + c]);
      }
    }
    const Cumulative read{cumulative.data()};
    Normals(6 * n_);
    for (int i = 0; i < n_; ++i) {
      const int parent = pf::SystematicParent(read, n_, u0, i);
      float p[6], q[6];
      Load(static_cast<size_t>(parent), p);
      pf::LiuWestMove(p, a, lw_shift, root, &normals_[6 * static_cast<size_t>(i)], q);
      for (int c = 0; c < 6; ++c) next_[c][static_cast<size_t>(i)] = q[c];
    }
    std::swap(x_, next_);
    SetEqualWeights();
    return Status::Ok();
  }

  // Absolute-coordinate state of a step's output.
  engine::TrackState State(const pf::StepOutput& out) const {
    engine::TrackState t;
    for (int r = 0; r < 6; ++r) {
      t.mean(r) = out.mean[r] + (r < 3 ? config_.origin_m[r] : 0.0);
      for (int c = 0; c < 6; ++c) t.covariance(r, c) = out.cov[r * 6 + c];
    }
    return t;
  }

 private:
  struct Cumulative {
    const double* c;
    double operator()(int j) const { return c[j]; }
  };
  uint32_t NextKey() {
    ++draws_;
    return engine::HashMix32(static_cast<uint32_t>(seed_) ^
                             engine::HashMix32(static_cast<uint32_t>(seed_ >> 32) + 0x9e3779b9U * draws_));
  }
  // Fills normals_[0, count) with standard normals from a fresh key.
  void Normals(int count) {
    normals_.resize(static_cast<size_t>(count) + 1);
    const uint32_t key = NextKey();
    for (int j = 0; j + 1 < count + 1; j += 2) {
      const uint32_t c = static_cast<uint32_t>(j);
      engine::NormalPairFromUniforms(engine::UniformFromCounter(key, c), engine::UniformFromCounter(key, c + 1),
                                     &normals_[static_cast<size_t>(j)], &normals_[static_cast<size_t>(j) + 1]);
    }
  }
  void Load(size_t i, float p[6]) const {
    for (int c = 0; c < 6; ++c) p[c] = x_[c][i];
  }
  void Store(size_t i, const float p[6]) {
    for (int c = 0; c < 6; ++c) x_[c][i] = p[c];
  }
  void SetEqualWeights() {
    logw_.assign(static_cast<size_t>(n_), -std::log(static_cast<float>(n_)));
    w_.assign(static_cast<size_t>(n_), 1.0f / static_cast<float>(n_));
  }

  pf::SessionConfig config_;
  int n_;
  uint64_t seed_;
  uint32_t draws_ = 0;
  std::vector<float> x_[6], next_[6], logw_, w_, normals_;
  double ess_ = 0.0;
};

}  // namespace localizer::gpu::testing
