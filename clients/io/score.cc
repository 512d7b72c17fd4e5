#include "clients/io/score.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

namespace localizer::io {

namespace {

Status CheckTruthOrder(const std::vector<engine::TruthRow>& truth) {
  if (truth.empty()) return InvalidArgument("truth has no rows");
  for (size_t i = 0; i < truth.size(); ++i) {
    if (!std::isfinite(truth[i].t_s)) {
      return InvalidArgument("truth row " + std::to_string(i) + ": t_s is not finite");
    }
    if (i > 0 && truth[i].t_s < truth[i - 1].t_s) {
      return InvalidArgument("truth rows are not ordered by t_s at row " + std::to_string(i));
    }
  }
  return Status::Ok();
}

// Truth position at t_s, which must lie within the truth span.
engine::Vec3 TruthPositionAt(const std::vector<engine::TruthRow>& truth, double t_s) {
  const auto after =
      std::upper_bound(truth.begin(), truth.end(), t_s, [](double t, const engine::TruthRow& r) { return t < r.t_s; });
  if (after == truth.begin()) return truth.front().position_m;
  if (after == truth.end()) return truth.back().position_m;
  const engine::TruthRow& a = *(after - 1);
  const engine::TruthRow& b = *after;
  const double w = (t_s - a.t_s) / (b.t_s - a.t_s);  // b.t_s > a.t_s since t_s >= a.t_s
  return (1.0 - w) * a.position_m + w * b.position_m;
}

ScoreResult Summarise(std::vector<double> errors_m) {
  std::sort(errors_m.begin(), errors_m.end());
  const size_t n = errors_m.size();
  double sum_sq = 0.0;
  for (double e : errors_m) sum_sq += e * e;
  ScoreResult score;
  score.count = static_cast<int64_t>(n);
  score.rmse_m = std::sqrt(sum_sq / static_cast<double>(n));
  score.median_m = n % 2 == 1 ? errors_m[n / 2] : 0.5 * (errors_m[n / 2 - 1] + errors_m[n / 2]);
  const size_t p95_rank = static_cast<size_t>(std::ceil(0.95 * static_cast<double>(n)));
  score.p95_m = errors_m[std::max<size_t>(p95_rank, 1) - 1];
  score.max_m = errors_m.back();
  return score;
}

}  // namespace

StatusOr<ScoreResult> Score(const std::vector<engine::TruthRow>& truth, const std::vector<EstimateRow>& estimates) {
  LOCALIZER_RETURN_IF_ERROR(CheckTruthOrder(truth));
  const double first_s = truth.front().t_s;
  const double last_s = truth.back().t_s;
  std::vector<double> errors_m;
  for (const EstimateRow& e : estimates) {
    if (!e.initialised || !(e.t_s >= first_s && e.t_s <= last_s)) continue;
    const double error_m = (e.position_m - TruthPositionAt(truth, e.t_s)).norm();
    errors_m.push_back(std::isfinite(error_m) ? error_m : std::numeric_limits<double>::infinity());
  }
  if (errors_m.empty()) {
    return FailedPrecondition("no initialised estimate within the truth span [" + std::to_string(first_s) + ", " +
                              std::to_string(last_s) + "] s (" + std::to_string(estimates.size()) + " estimates)");
  }
  return Summarise(std::move(errors_m));
}

std::string FormatScore(const ScoreResult& score) {
  std::string line = "n=" + std::to_string(score.count);
  const std::pair<const char*, double> fields[] = {
      {"rmse_m", score.rmse_m}, {"median_m", score.median_m}, {"p95_m", score.p95_m}, {"max_m", score.max_m}};
  for (const auto& [name, value] : fields) {
    char number[32];
    std::snprintf(number, sizeof(number), "%.6g", value);  // 1 um at 1 m; enough to compare
    line += std::string(", ") + name + "=" + number;
  }
  return line;
}

}  // namespace localizer::io
