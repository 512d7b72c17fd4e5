#include "engine/pipeline/scene_campaign.h"

#include <Eigen/Cholesky>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <numbers>

#include "engine/array/multilateration.h"
#include "engine/pipeline/range_observability.h"

namespace localizer::engine {
namespace {

constexpr double kMadToSigma = 1.4826;  // Gaussian std per median absolute deviation
constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kNan = std::numeric_limits<double>::quiet_NaN();

double Median(std::vector<double> values) { return Quantile(std::move(values), 0.5); }

double PositionNees(const Estimate& e, const Vec3& error_m) {
  const Mat3 p = e.covariance.topLeftCorner<3, 3>();
  const Eigen::LLT<Mat3> llt(p);
  if (llt.info() != Eigen::Success || !p.allFinite()) return kInf;
  const double nees = error_m.dot(llt.solve(error_m));
  return std::isfinite(nees) && nees >= 0.0 ? nees : kInf;
}

// 1.4826 x MAD per pair of (measured - true) TDOA over the frames inside the truth.
std::vector<double> RobustTdoaSigma(const ArrayGeometry& array, const SimResult& sim,
                                    const std::vector<Estimate>& estimates, double t_end_s) {
  const int pairs = array.pair_count();
  std::vector<std::vector<double>> errors(pairs);
  for (const Estimate& e : estimates) {
    if (e.t_s > t_end_s || static_cast<int>(e.delay_s.size()) != pairs) continue;
    for (int p = 0; p < pairs; ++p) {
      if (!std::isfinite(e.delay_s[p])) continue;
      const Vec3 at = sim.TruthAt(e.t_s - 0.5 * e.delay_s[p]).position_m;
      errors[p].push_back(e.delay_s[p] - array.Tdoa(at)(p));
    }
  }
  const double floor_s = 1e-3 / sim.sample_rate_hz;
  std::vector<double> sigma;
  for (std::vector<double>& err : errors) {
    if (err.empty()) return {};
    const double centre = Median(err);
    for (double& x : err) x = std::abs(x - centre);
    sigma.push_back(std::max(kMadToSigma * Median(err), floor_s));
  }
  return sigma;
}

// The position bound's covariance at a point (NaN without one sigma per pair).
Mat3 CrlbCovariance(const ArrayGeometry& array, const Vec3& at_m, const std::vector<double>& sigma_s) {
  if (static_cast<int>(sigma_s.size()) != array.pair_count()) return Mat3::Constant(kNan);
  const Eigen::VectorXd sigma = Eigen::Map<const Eigen::VectorXd>(sigma_s.data(), array.pair_count());
  return TdoaPositionCrlb(array, at_m, sigma);
}

double Crlb(const ArrayGeometry& array, const Vec3& at_m, const std::vector<double>& sigma_s) {
  return std::sqrt(CrlbCovariance(array, at_m, sigma_s).trace());
}

// The bearing's bound: the position bound's covariance across the line of sight from the
// centroid, over the range.
double BearingCrlb(const ArrayGeometry& array, const Vec3& at_m, const Mat3& crlb_covariance) {
  const Vec3 line_m = at_m - array.centroid_m();
  const double range_m = line_m.norm();
  if (!(range_m > 0.0)) return kNan;
  const Vec3 u = line_m / range_m;
  const Mat3 across = Mat3::Identity() - u * u.transpose();
  return std::sqrt((across * crlb_covariance * across).trace()) / range_m;
}

// A far-field claim where the truth's own bound holds the range to better than a sixth of
// itself (half the engine's kFarFieldRangeShare) withholds a range the data held.
bool WithholdsRange(const FrameScore& f) { return f.far_field && f.range_share < kFarFieldRangeShare / 2.0; }

double AngleBetween(const Vec3& a, const Vec3& b) { return std::atan2(a.cross(b).norm(), a.dot(b)); }

// Median spacing of the frames: the time one frame stands for.
double HopSeconds(const std::vector<Estimate>& estimates) {
  std::vector<double> steps;
  for (size_t i = 1; i < estimates.size(); ++i) steps.push_back(estimates[i].t_s - estimates[i - 1].t_s);
  return steps.empty() ? 0.0 : Median(steps);
}

// The first frame from which every counted, initialised frame with a finite `bound` has
// error <= multiple x bound to the end; -1 when there is none.
int AcquiredFrom(const std::vector<FrameScore>& frames, double FrameScore::*bound, double multiple,
                 double FrameScore::*error = &FrameScore::error_m) {
  auto judged = [&](const FrameScore& f) { return f.counted && f.initialised && std::isfinite(f.*bound); };
  const auto n = static_cast<int>(frames.size());
  int last_bad = -1;
  for (int i = 0; i < n; ++i) {
    if (judged(frames[i]) && !(frames[i].*error <= multiple * (frames[i].*bound))) last_bad = i;
  }
  for (int i = last_bad + 1; i < n; ++i) {
    if (judged(frames[i])) return i;
  }
  return -1;
}

}  // namespace

double Quantile(std::vector<double> values, double q) {
  values.erase(std::remove_if(values.begin(), values.end(), [](double v) { return std::isnan(v); }), values.end());
  if (values.empty()) return kNan;
  std::sort(values.begin(), values.end());
  const auto rank = static_cast<size_t>(std::max(1.0, std::ceil(q * static_cast<double>(values.size()))));
  return values[std::min(rank, values.size()) - 1];
}

SceneScore ScoreScene(const ArrayGeometry& array, const SimResult& sim, const std::vector<Estimate>& estimates,
                      const std::vector<double>& theory_sigma_s, const SceneScoreOptions& options) {
  SceneScore score;
  score.frames = static_cast<int>(estimates.size());
  const double t_end_s = sim.truth.empty() ? 0.0 : sim.truth.back().t_s;
  for (const Estimate& e : estimates) score.presence_reported |= e.presence_threshold > 0.0;
  score.tdoa_sigma_robust_s = RobustTdoaSigma(array, sim, estimates, t_end_s);
  score.tdoa_sigma_theory_s = theory_sigma_s;

  std::vector<double> crlbs, theory_crlbs, ranges;
  for (const Estimate& e : estimates) {
    FrameScore f;
    f.t_s = e.t_s;
    f.initialised = e.initialised;
    f.present = e.source_present;
    f.ambiguous = e.ambiguous;
    f.pairs_used = e.pairs_used;
    f.nis = e.nis;
    f.tdoa_sigma_s = e.tdoa_sigma_s;
    for (size_t p = 0; p < e.delay_s.size() && static_cast<int>(p) < array.pair_count(); ++p) {
      const Vec3 at = sim.TruthAt(e.t_s - 0.5 * e.delay_s[p]).position_m;
      f.tdoa_error_s.push_back(e.delay_s[p] - array.Tdoa(at)(static_cast<int>(p)));
    }
    f.counted = e.t_s <= t_end_s && (!score.presence_reported || e.source_present);
    const Vec3 truth_m = sim.TruthAt(e.t_s).position_m;
    const Mat3 crlb_covariance = CrlbCovariance(array, truth_m, score.tdoa_sigma_robust_s);
    f.crlb_m = std::sqrt(crlb_covariance.trace());
    f.crlb_theory_m = Crlb(array, truth_m, theory_sigma_s);
    f.bearing_crlb_rad = BearingCrlb(array, truth_m, crlb_covariance);
    f.range_m = (truth_m - array.centroid_m()).norm();
    f.range_apertures = f.range_m / array.aperture_m();
    if (f.counted) {
      crlbs.push_back(f.crlb_m);
      theory_crlbs.push_back(f.crlb_theory_m);
      ranges.push_back(f.range_apertures);
    }
    f.range_share = RangeSd(array, truth_m, crlb_covariance) / f.range_m;
    if (e.initialised) {
      ++score.initialised_frames;
      const Vec3 error = e.state.head<3>() - truth_m;
      f.error_m = error.norm();
      f.range_error_m = (e.state.head<3>() - array.centroid_m()).norm() - f.range_m;
      f.bearing_error_rad = AngleBetween(e.state.head<3>() - array.centroid_m(), truth_m - array.centroid_m());
      f.nees_position = PositionNees(e, error);
      f.sd_m = std::sqrt(e.covariance.topLeftCorner<3, 3>().trace());
      f.far_field = e.far_field;
      f.bearing_sd_rad = BearingCrlb(array, e.state.head<3>(), e.covariance.topLeftCorner<3, 3>());
      // A far-field claim is honoured where the truth's own bound agrees the range is weak.
      const bool in_bearing = e.far_field && !WithholdsRange(f);
      f.reported_error = in_bearing ? f.bearing_error_rad : f.error_m;
      f.reported_bound = in_bearing ? f.bearing_crlb_rad : f.crlb_m;
    }
    score.per_frame.push_back(f);
  }
  score.crlb_median_m = Median(crlbs);
  score.crlb_theory_median_m = Median(theory_crlbs);
  score.range_apertures_median = Median(ranges);

  // Frames whose error is compared (counted, initialised, with a bound).
  auto judged = [](const FrameScore& f) { return f.counted && f.initialised && std::isfinite(f.crlb_m); };
  const auto n = static_cast<int>(score.per_frame.size());
  const int acquired_at = AcquiredFrom(score.per_frame, &FrameScore::crlb_m, options.acquire_crlb_multiple);
  const int acquired_theory_at =
      AcquiredFrom(score.per_frame, &FrameScore::crlb_theory_m, options.acquire_crlb_multiple);
  const int acquired_bearing_at = AcquiredFrom(score.per_frame, &FrameScore::bearing_crlb_rad,
                                               options.acquire_crlb_multiple, &FrameScore::bearing_error_rad);
  if (acquired_bearing_at >= 0) {
    score.acquired_bearing = true;
    score.time_to_acquire_bearing_s = score.per_frame[acquired_bearing_at].t_s;
  }
  const int acquired_reported_at = AcquiredFrom(score.per_frame, &FrameScore::reported_bound,
                                                options.acquire_crlb_multiple, &FrameScore::reported_error);
  if (acquired_reported_at >= 0) {
    score.acquired_reported = true;
    score.time_to_acquire_reported_s = score.per_frame[acquired_reported_at].t_s;
  }
  if (acquired_theory_at >= 0) {
    score.acquired_theory = true;
    score.time_to_acquire_theory_s = score.per_frame[acquired_theory_at].t_s;
  }
  if (acquired_at >= 0) {
    score.acquired = true;
    score.time_to_acquire_s = score.per_frame[acquired_at].t_s;
    double sum_sq = 0.0, sum_sq_theory = 0.0;
    int counted = 0, initialised = 0;
    std::vector<double> errors, nees;
    for (int i = acquired_at; i < n; ++i) {
      const FrameScore& f = score.per_frame[i];
      if (!f.counted) continue;
      ++counted;
      if (!judged(f)) continue;
      ++initialised;
      sum_sq += (f.error_m / f.crlb_m) * (f.error_m / f.crlb_m);
      sum_sq_theory += (f.error_m / f.crlb_theory_m) * (f.error_m / f.crlb_theory_m);
      errors.push_back(f.error_m);
      nees.push_back(f.nees_position / 3.0);
    }
    score.rmse_over_crlb = std::sqrt(sum_sq / initialised);
    score.rmse_over_crlb_theory = std::sqrt(sum_sq_theory / initialised);  // NaN without theory
    score.median_error_m = Median(errors);
    score.median_nees_per_dim = Median(nees);
    score.initialised_after_acquire = counted > 0 ? static_cast<double>(initialised) / counted : kNan;
  }

  // Lost: after the first frame that looked acquired, frames far outside the bound.
  int first_good = -1;
  for (int i = 0; i < n && first_good < 0; ++i) {
    const FrameScore& f = score.per_frame[i];
    if (judged(f) && f.error_m <= options.acquire_crlb_multiple * f.crlb_m) first_good = i;
  }
  for (int i = std::max(first_good, 0); first_good >= 0 && i < n; ++i) {
    const FrameScore& f = score.per_frame[i];
    if (judged(f) && f.error_m > options.lost_crlb_multiple * f.crlb_m) ++score.lost_frames;
  }

  // Silent failure: badly wrong, claiming a resolved, present source with a covariance that
  // does not cover the error.
  const double hop_s = HopSeconds(estimates);
  for (int i = 0; i < n; ++i) {
    FrameScore& f = score.per_frame[i];
    if (!judged(f) || estimates[i].ambiguous) continue;
    f.silent = f.error_m > options.lost_crlb_multiple * f.crlb_m && f.nees_position > options.silent_nees;
    if (f.silent) score.silent_failure_s += hop_s;
  }
  score.silent_failure = score.silent_failure_s > options.silent_min_s;

  // As reported: far-field frames answer for their bearing, and must not withhold a range
  // the data held.
  for (int i = 0; i < n; ++i) {
    const FrameScore& f = score.per_frame[i];
    if (!judged(f)) continue;
    const bool withheld = WithholdsRange(f);
    score.far_field_frames += f.far_field;
    if (withheld) score.range_withheld_s += hop_s;
    if (!f.far_field || withheld) {
      if (!estimates[i].ambiguous && f.error_m > options.lost_crlb_multiple * f.crlb_m &&
          f.nees_position > options.silent_nees) {
        score.silent_failure_reported_s += hop_s;
      }
      continue;
    }
    if (!estimates[i].ambiguous && f.bearing_error_rad > options.lost_crlb_multiple * f.bearing_crlb_rad &&
        !(f.bearing_error_rad <= 3.0 * f.bearing_sd_rad)) {
      score.silent_failure_reported_s += hop_s;
    }
  }
  score.silent_failure_reported = score.silent_failure_reported_s > options.silent_min_s;
  return score;
}

std::vector<double> TheoreticalTdoaSigma(const SimOptions& sim, int pair_count, int frame_samples) {
  if (sim.signal == SourceSignal::kClicks || sim.snr_db >= kNoNoiseSnrDb || pair_count <= 0) return {};
  const double fs = sim.sample_rate_hz;
  const double lo = sim.band_low_hz, hi = sim.band_high_hz;
  const double broadband_share = sim.signal == SourceSignal::kTonalBroadband ? 1.0 - sim.tone_power_fraction : 1.0;
  if (broadband_share <= 0.0) return {};
  const double snr_f = broadband_share * std::pow(10.0, sim.snr_db / 10.0) * (0.5 * fs) / (hi - lo);
  const double weight = snr_f * snr_f / (1.0 + 2.0 * snr_f);
  const double t_s = frame_samples / fs;
  const double four_pi_sq = 4.0 * std::numbers::pi * std::numbers::pi;
  const double information = 2.0 * t_s * weight * four_pi_sq * (hi * hi * hi - lo * lo * lo) / 3.0;
  return std::vector<double>(pair_count, 1.0 / std::sqrt(information));
}

AudioSessionConfig CampaignSessionConfig(const RandomScene& scene) {
  AudioSessionConfig config;
  config.sensors_m = scene.scenario.sensors_m;
  config.sound_speed_mps = scene.scenario.sound_speed_mps;
  config.sample_rate_hz = scene.scenario.sim.sample_rate_hz;
  // About a quarter second per frame whatever the rate: 4096 up to 16 kHz, 16384 at 48 kHz.
  int scale = 1;
  while (16000.0 * scale < config.sample_rate_hz) scale *= 2;
  config.frame_samples = 4096 * scale;
  config.hop_samples = config.frame_samples / 2;
  config.band_low_hz = 0.0;  // no band hint: users do not know their source's band
  config.band_high_hz = 0.0;
  config.backend = BackendChoice::kCpu;
  config.seed = scene.seed;
  return config;
}

SceneRow RunRandomScene(uint64_t seed, const RandomSceneOptions& scene_options, const SceneScoreOptions& score_options,
                        bool keep_frames, const std::function<void(AudioSessionConfig*)>& adjust) {
  const auto start = std::chrono::steady_clock::now();
  SceneRow row;
  row.seed = seed;
  auto fail = [&](const Status& status) {
    row.error = status.ToString();
    row.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return row;
  };
  auto scene = DrawRandomScene(seed, scene_options);
  if (!scene.ok()) return fail(scene.status());
  row.scene_class = scene->scene_class;
  row.description = scene->scenario.description;
  auto array = ArrayGeometry::Create(scene->scenario.sensors_m, scene->scenario.sound_speed_mps);
  if (!array.ok()) return fail(array.status());
  auto sim = Simulate(*array, scene->scenario.sim);
  if (!sim.ok()) return fail(sim.status());
  AudioSessionConfig config = CampaignSessionConfig(*scene);
  if (adjust) adjust(&config);
  auto session = Session::Create(config);
  if (!session.ok()) return fail(session.status());
  std::vector<Estimate> estimates;
  const Status processed =
      (*session)->Process({1, sim->channel_count, sim->samples_per_channel, sim->samples.data()}, &estimates);
  if (!processed.ok()) return fail(processed);
  row.score =
      ScoreScene(*array, *sim, estimates,
                 TheoreticalTdoaSigma(scene->scenario.sim, array->pair_count(), config.frame_samples), score_options);
  if (!keep_frames) row.score.per_frame.clear();
  row.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return row;
}

CampaignSummary SummariseCampaign(std::vector<SceneRow> rows) {
  CampaignSummary s;
  std::vector<double> times_theory, times_reported;
  std::vector<double> times_all, times_acquired, nees, rmse_gaussian, rmse_hard, rmse_theory, errors;
  std::vector<double> rmse_class[3];
  ClassSummary* classes[3] = {&s.gaussian, &s.multipath, &s.impulsive};
  for (const SceneRow& row : rows) {
    ++s.scenes;
    if (!row.error.empty()) {
      ++s.run_errors;
      continue;
    }
    const SceneScore& score = row.score;
    const int c = static_cast<int>(row.scene_class);
    ++classes[c]->scenes;
    times_all.push_back(score.time_to_acquire_s);
    times_theory.push_back(score.time_to_acquire_theory_s);
    if (score.acquired_theory) ++s.acquired_theory;
    if (score.acquired_bearing) {
      ++s.acquired_bearing;
      if (!score.acquired) {
        ++s.acquired_bearing_not_position;
        if (score.range_apertures_median > 3.0) ++s.acquired_bearing_not_position_far;
      }
    }
    if (score.lost_frames > 0) ++s.lost;
    if (score.silent_failure) ++s.silent_failures;
    if (score.silent_failure_reported) ++s.silent_failures_reported;
    if (score.acquired_reported) ++s.acquired_reported;
    if (score.range_withheld_s > 1.0) ++s.range_withheld;
    times_reported.push_back(score.time_to_acquire_reported_s);
    if (!score.acquired) continue;
    ++s.acquired;
    ++classes[c]->acquired;
    times_acquired.push_back(score.time_to_acquire_s);
    nees.push_back(score.median_nees_per_dim);
    rmse_theory.push_back(score.rmse_over_crlb_theory);
    errors.push_back(score.median_error_m);
    rmse_class[c].push_back(score.rmse_over_crlb);
    (row.scene_class == SceneClass::kGaussian ? rmse_gaussian : rmse_hard).push_back(score.rmse_over_crlb);
  }
  s.median_time_to_acquire_s = Quantile(times_all, 0.5);
  s.p95_time_to_acquire_s = Quantile(times_all, 0.95);
  s.median_time_to_acquire_theory_s = Quantile(times_theory, 0.5);
  s.median_time_to_acquire_reported_s = Quantile(times_reported, 0.5);
  s.p95_time_to_acquire_reported_s = Quantile(times_reported, 0.95);
  s.median_time_to_acquire_acquired_s = Quantile(times_acquired, 0.5);
  s.p95_time_to_acquire_acquired_s = Quantile(times_acquired, 0.95);
  s.median_rmse_over_crlb_gaussian = Median(rmse_gaussian);
  s.median_rmse_over_crlb_hard = Median(rmse_hard);
  for (int c = 0; c < 3; ++c) classes[c]->median_rmse_over_crlb = Median(rmse_class[c]);
  s.median_nees_per_dim = Median(nees);
  s.median_rmse_over_crlb_theory = Median(rmse_theory);
  s.median_error_m = Median(errors);
  s.rows = std::move(rows);
  return s;
}

}  // namespace localizer::engine
