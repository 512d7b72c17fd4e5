#include "engine/experiments/pf_vs_ekf_2d.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <numeric>
#include <tuple>

#include "engine/experiments/experiment_random.h"
#include "engine/experiments/planar_kalman.h"
#include "engine/experiments/planar_particle.h"
#include "engine/sim/invalid_value.h"

namespace localizer::engine::experiments {
namespace {

constexpr int kMaxRuns = 1000000;
constexpr int kMaxParticles = 1000000;

bool PositiveFinite(double value) { return value > 0.0 && std::isfinite(value); }
bool NonNegativeFinite(double value) { return value >= 0.0 && std::isfinite(value); }

Status Invalid(const std::string& field, double value, const std::string& requirement) {
  return sim_detail::Invalid(field, value, requirement);
}

int FilterIndex(const std::string& name) {
  const std::vector<std::string> names = PfVsEkf2dFilterNames();
  const auto it = std::find(names.begin(), names.end(), name);
  return it == names.end() ? -1 : static_cast<int>(it - names.begin());
}

std::vector<std::string> SelectedFilters(const PfVsEkf2dOptions& options) {
  return options.filters.empty() ? PfVsEkf2dFilterNames() : options.filters;
}

// The filter names, and what the chosen filters need of the noise.
Status ValidateFilters(const PfVsEkf2dOptions& options) {
  for (const std::string& name : options.filters) {
    if (FilterIndex(name) < 0) {
      std::string known;
      for (const std::string& n : PfVsEkf2dFilterNames()) known += (known.empty() ? "" : ", ") + n;
      return InvalidArgument("filters has unknown filter \"" + name + "\"; known: " + known);
    }
  }
  const std::vector<std::string> selected = SelectedFilters(options);
  const double alpha = options.measurement_noise.stable.alpha;
  if (std::find(selected.begin(), selected.end(), "PF") != selected.end() && !(alpha > 1.0)) {
    return Invalid("alpha", alpha, "the PF's stable density needs alpha > 1 (or leave PF out of filters)");
  }
  return Status::Ok();
}

PlanarKalmanOptions KalmanOptions(const PfVsEkf2dOptions& options, PlanarPredictor predictor, PlanarUpdater updater) {
  PlanarKalmanOptions kalman;
  kalman.predictor = predictor;
  kalman.updater = updater;
  kalman.measurement_sigma_m = options.KalmanSigma();
  kalman.huber_threshold = options.huber_threshold;
  kalman.student_dof = options.student_dof;
  return kalman;
}

// Mean and population std of `values`.
std::pair<double, double> MeanAndStd(const std::vector<double>& values) {
  const double n = static_cast<double>(values.size());
  const double mean = std::accumulate(values.begin(), values.end(), 0.0) / n;
  double squares = 0.0;
  for (double v : values) squares += (v - mean) * (v - mean);
  return {mean, std::sqrt(squares / n)};
}

double Median(std::vector<double> values) {
  const size_t mid = values.size() / 2;
  std::nth_element(values.begin(), values.begin() + mid, values.end());
  if (values.size() % 2 == 1) return values[mid];
  const double upper = values[mid];
  return 0.5 * (upper + *std::max_element(values.begin(), values.begin() + mid));
}

// What one filter accumulates over the runs.
struct FilterTally {
  std::vector<double> step_errors;  // pooled over runs
  std::vector<double> run_means;
  std::vector<double> final_lap_means;
  double seconds = 0.0;
};

FilterSummary Summarise(const std::string& name, const FilterTally& tally, double divergence_m) {
  FilterSummary s;
  s.name = name;
  std::tie(s.mean_error_m, s.step_std_m) = MeanAndStd(tally.step_errors);
  s.run_std_m = MeanAndStd(tally.run_means).second;
  s.median_error_m = Median(tally.step_errors);
  s.final_lap_error_m = MeanAndStd(tally.final_lap_means).first;
  s.divergences = static_cast<int>(std::count_if(tally.final_lap_means.begin(), tally.final_lap_means.end(),
                                                 [&](double e) { return e > divergence_m; }));
  s.us_per_step = 1e6 * tally.seconds / static_cast<double>(tally.step_errors.size());
  return s;
}

}  // namespace

std::vector<std::string> PfVsEkf2dFilterNames() {
  return {"PF", "PF-Gauss", "EKF", "UKF", "EKF-Huber", "UKF-Huber", "EKF-t"};
}

Status PfVsEkf2dOptions::Validate() const {
  if (runs < 1 || runs > kMaxRuns) return Invalid("runs", runs, "must be in [1, 1000000]");
  if (particles < 1 || particles > kMaxParticles) {
    return Invalid("particles", particles, "must be in [1, 1000000]");
  }
  LOCALIZER_RETURN_IF_ERROR(course.Validate(model));
  LOCALIZER_RETURN_IF_ERROR(control_noise.Validate());
  LOCALIZER_RETURN_IF_ERROR(measurement_noise.Validate());
  if (!(resample_ess_fraction >= 0.0 && resample_ess_fraction <= 1.0)) {
    return Invalid("resample_ess_fraction", resample_ess_fraction, "must be in [0, 1]");
  }
  if (!NonNegativeFinite(kalman_sigma_m)) {
    return Invalid("kalman_sigma_m", kalman_sigma_m, "must be >= 0 (0: the Gaussian sigma)");
  }
  if (!PositiveFinite(huber_threshold)) {
    return Invalid("huber_threshold", huber_threshold, "must be positive");
  }
  if (!PositiveFinite(student_dof)) return Invalid("student_dof", student_dof, "must be positive");
  if (!NonNegativeFinite(initial_position_sigma_m)) {
    return Invalid("initial_position_sigma_m", initial_position_sigma_m, "must be >= 0");
  }
  if (!NonNegativeFinite(initial_heading_sigma_rad)) {
    return Invalid("initial_heading_sigma_rad", initial_heading_sigma_rad, "must be >= 0");
  }
  if (!PositiveFinite(divergence_error_m)) {
    return Invalid("divergence_error_m", divergence_error_m, "must be positive");
  }
  return ValidateFilters(*this);
}

StatusOr<PlanarRun> SimulatePlanarRun(const PfVsEkf2dOptions& options, int64_t run) {
  LOCALIZER_RETURN_IF_ERROR(options.Validate());
  StatusOr<CourseSchedule> course = RoundedRectangleCourse(options.course, options.model);
  if (!course.ok()) return course.status();
  std::mt19937_64 control_engine = ExperimentEngine(options.seed, ExperimentStream::kControlNoise, run);
  std::mt19937_64 fix_engine = ExperimentEngine(options.seed, ExperimentStream::kMeasurementNoise, run);
  PlanarRun r;
  r.commands = std::move(course->controls);
  r.truth.reserve(r.commands.size() + 1);
  r.fixes_m.reserve(r.commands.size());
  r.truth.push_back(PlanarState::Zero());
  for (const BicycleControl& command : r.commands) {
    const ControlNoise& w = options.control_noise;
    const double speed = command.speed_mps + w.speed_sigma_mps * StandardNormal(control_engine);
    const double steering = command.steering_rad + w.steering_sigma_rad * StandardNormal(control_engine);
    r.truth.push_back(options.model.Step(r.truth.back(), {speed, steering}, options.course.dt_s));
    r.fixes_m.push_back(r.truth.back().head<2>() + SampleMixtureNoise(options.measurement_noise, fix_engine));
  }
  return r;
}

StatusOr<std::unique_ptr<PlanarFilter>> MakePlanarFilter(const std::string& name, const PfVsEkf2dOptions& options,
                                                         std::shared_ptr<const MixtureDensity> mixture, int64_t run) {
  const int index = FilterIndex(name);
  if (index < 0) return InvalidArgument("filter \"" + name + "\" is unknown");
  const auto wrap = [](auto made) -> StatusOr<std::unique_ptr<PlanarFilter>> {
    if (!made.ok()) return made.status();
    return std::unique_ptr<PlanarFilter>(std::move(*made));
  };
  if (name == "PF" || name == "PF-Gauss") {
    PlanarParticleOptions pf;
    pf.particles = options.particles;
    pf.likelihood = name == "PF" ? ParticleLikelihood::kMixture : ParticleLikelihood::kGaussian;
    pf.gaussian_sigma_m = options.KalmanSigma();
    pf.resample_ess_fraction = options.resample_ess_fraction;
    std::mt19937_64 engine =
        ExperimentEngine(options.seed, ExperimentStream::kFilter, run, static_cast<uint32_t>(index));
    return wrap(PlanarParticleFilter::Create(options.model, options.control_noise, pf, std::move(mixture), engine));
  }
  const PlanarPredictor predictor = name.starts_with("UKF") ? PlanarPredictor::kUnscented : PlanarPredictor::kExtended;
  const PlanarUpdater updater = name.ends_with("-Huber") ? PlanarUpdater::kHuber
                                : name.ends_with("-t")   ? PlanarUpdater::kStudentT
                                                         : PlanarUpdater::kGaussian;
  return wrap(
      PlanarKalmanFilter::Create(options.model, options.control_noise, KalmanOptions(options, predictor, updater)));
}

std::vector<double> TrackPlanarRun(PlanarFilter& filter, const PfVsEkf2dOptions& options, const PlanarRun& run) {
  PlanarBelief prior;
  prior.mean = run.truth.front();
  const double sp = options.initial_position_sigma_m, sh = options.initial_heading_sigma_rad;
  prior.covariance.diagonal() << sp * sp, sp * sp, sh * sh;
  filter.Initialise(prior);
  std::vector<double> errors(run.commands.size());
  for (size_t k = 0; k < run.commands.size(); ++k) {
    filter.Predict(run.commands[k], options.course.dt_s);
    filter.Update(run.fixes_m[k]);
    errors[k] = (filter.Estimate().head<2>() - run.truth[k + 1].head<2>()).norm();
  }
  return errors;
}

StatusOr<PfVsEkf2dResult> RunPfVsEkf2d(const PfVsEkf2dOptions& options, const std::function<void(int)>& progress) {
  LOCALIZER_RETURN_IF_ERROR(options.Validate());
  const std::vector<std::string> names = SelectedFilters(options);
  std::shared_ptr<const MixtureDensity> mixture;
  if (std::find(names.begin(), names.end(), "PF") != names.end()) {
    StatusOr<MixtureDensity> density = MixtureDensity::Create(options.measurement_noise);
    if (!density.ok()) return density.status();
    mixture = std::make_shared<const MixtureDensity>(std::move(*density));
  }
  PfVsEkf2dResult result;
  result.runs = options.runs;
  std::vector<FilterTally> tallies(names.size());
  for (int run = 0; run < options.runs; ++run) {
    StatusOr<PlanarRun> simulated = SimulatePlanarRun(options, run);
    if (!simulated.ok()) return simulated.status();
    result.steps_per_run = static_cast<int>(simulated->commands.size());
    result.steps_per_lap = result.steps_per_run / options.course.laps;
    for (size_t f = 0; f < names.size(); ++f) {
      StatusOr<std::unique_ptr<PlanarFilter>> filter = MakePlanarFilter(names[f], options, mixture, run);
      if (!filter.ok()) return filter.status();
      const auto start = std::chrono::steady_clock::now();
      const std::vector<double> errors = TrackPlanarRun(**filter, options, *simulated);
      tallies[f].seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      tallies[f].step_errors.insert(tallies[f].step_errors.end(), errors.begin(), errors.end());
      tallies[f].run_means.push_back(MeanAndStd(errors).first);
      const std::vector<double> final_lap(errors.end() - result.steps_per_lap, errors.end());
      tallies[f].final_lap_means.push_back(MeanAndStd(final_lap).first);
    }
    if (progress) progress(run + 1);
  }
  for (size_t f = 0; f < names.size(); ++f) {
    result.filters.push_back(Summarise(names[f], tallies[f], options.divergence_error_m));
  }
  return result;
}

}  // namespace localizer::engine::experiments
