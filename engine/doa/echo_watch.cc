#include "engine/doa/echo_watch.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>

namespace localizer::engine {
namespace {

// The largest value of `lags` and its lag (index + 1).
std::pair<double, int> Best(const std::vector<double>& lags) {
  const auto it = std::max_element(lags.begin(), lags.end());
  if (it == lags.end()) return {0.0, 0};
  return {*it, static_cast<int>(it - lags.begin()) + 1};
}

// A running mean over the first 1 / w values, then an exponential average with weight w.
void Average(double now, int count, double w, double* mean) { *mean += std::max(w, 1.0 / count) * (now - *mean); }

}  // namespace

Status EchoWatchOptions::Validate() const {
  LOCALIZER_RETURN_IF_ERROR(test.Validate());
  if (!(averaging > 0.0 && averaging <= 1.0)) return InvalidArgument("averaging must be in (0, 1]");
  if (min_frames < 1) return InvalidArgument("min_frames must be at least 1");
  if (!(min_rho > 0.0 && min_rho < 1.0)) return InvalidArgument("min_rho must be in (0, 1)");
  if (!(min_envelope_correlation >= -1.0 && min_envelope_correlation <= 1.0))
    return InvalidArgument("min_envelope_correlation must be in [-1, 1]");
  if (!(envelope_averaging > 0.0 && envelope_averaging <= 1.0))
    return InvalidArgument("envelope_averaging must be in (0, 1]");
  if (independent_run_frames < 1) return InvalidArgument("independent_run_frames must be at least 1");
  return Status::Ok();
}

StatusOr<EchoWatch> EchoWatch::Create(const std::vector<Vec3>& sensors_m, const ArrayShapeInfo& shape,
                                      const EchoWatchOptions& options) {
  LOCALIZER_RETURN_IF_ERROR(options.Validate());
  auto test = EchoTest::Create(sensors_m, options.test);
  if (!test.ok()) return test.status();
  return EchoWatch(std::move(test).value(), shape, options);
}

Vec3 EchoWatch::DirectionOf(const SourceTrack& track) const {
  if (!std::isfinite(track.cone_angle_rad)) return track.direction;
  // Collinear sensors see only the projection on the axis: any direction at the cone angle.
  const Vec3& axis = shape_.axis;
  Vec3 across = axis.cross(Vec3::UnitZ());
  if (across.norm() < 1e-6) across = axis.cross(Vec3::UnitX());
  return std::cos(track.cone_angle_rad) * axis + std::sin(track.cone_angle_rad) * across.normalized();
}

double EchoWatch::Pair::EnvelopeCorrelation() const {
  const double norm = std::sqrt(change_a_sq * change_b_sq);
  return norm > 0.0 ? change_product / norm : 0.0;
}

void EchoWatch::Pair::AddEnvelopes(const EchoEvidence& e, int64_t frame, double min_weight) {
  double log_a[kBands], log_b[kBands];
  for (int q = 0; q < kBands; ++q) {
    log_a[q] = std::log(std::max(e.band_power_i[q], 1e-300));
    log_b[q] = std::log(std::max(e.band_power_j[q], 1e-300));
  }
  if (last_frame == frame - 1) {  // consecutive frames: the envelopes' changes, pooled over sub-bands
    double aa = 0.0, bb = 0.0, ab = 0.0;
    for (int q = 0; q < kBands; ++q) {
      const double da = log_a[q] - log_power_a[q], db = log_b[q] - log_power_b[q];
      aa += da * da, bb += db * db, ab += da * db;
    }
    ++envelope_frames;
    Average(aa, envelope_frames, min_weight, &change_a_sq);
    Average(bb, envelope_frames, min_weight, &change_b_sq);
    Average(ab, envelope_frames, min_weight, &change_product);
  }
  std::copy(log_a, log_a + kBands, log_power_a);
  std::copy(log_b, log_b + kBands, log_power_b);
  last_frame = frame;
}

void EchoWatch::Frame(const float* frame, const std::vector<SourceTrack>& tracks, const std::vector<char>& heard) {
  const auto reported = [&](uint64_t id) {
    return std::any_of(tracks.begin(), tracks.end(), [&](const SourceTrack& t) { return t.id == id; });
  };
  for (auto it = pairs_.begin(); it != pairs_.end();) {  // forget pairs whose tracks are gone
    it = reported(it->first.first) && reported(it->first.second) ? std::next(it) : pairs_.erase(it);
  }
  bool loaded = false;
  for (size_t a = 0; a < tracks.size(); ++a) {
    for (size_t b = 0; b < tracks.size(); ++b) {
      if (tracks[a].id >= tracks[b].id || !(heard[a] || heard[b])) continue;
      Pair& p = pairs_[{tracks[a].id, tracks[b].id}];
      p.a_run = heard[a] && !heard[b] ? p.a_run + 1 : 0;
      p.b_run = heard[b] && !heard[a] ? p.b_run + 1 : 0;
      p.a_independent = p.a_independent || p.a_run >= options_.independent_run_frames;
      p.b_independent = p.b_independent || p.b_run >= options_.independent_run_frames;
      if (!heard[a] || !heard[b]) continue;
      const Vec3 ua = DirectionOf(tracks[a]), ub = DirectionOf(tracks[b]);
      if (!ua.allFinite() || !ub.allFinite()) continue;
      if (!loaded) test_.Load(frame), loaded = true;
      if (!test_.Compare(ua, ub, &evidence_)) continue;  // the two directions are not told apart
      ++p.frames;
      const auto average = [&](const std::vector<double>& now, std::vector<double>* mean) {
        if (mean->size() != now.size()) mean->assign(now.size(), 0.0);
        for (size_t k = 0; k < now.size(); ++k) Average(now[k], p.frames, options_.averaging, &(*mean)[k]);
      };
      average(evidence_.lagging, &p.b_lags);  // b's beam behind a's
      average(evidence_.leading, &p.a_lags);
      Average(evidence_.power_j / (evidence_.power_i + evidence_.power_j), p.frames, options_.averaging, &p.b_share);
      p.AddEnvelopes(evidence_, frame_, options_.envelope_averaging);
    }
  }
  echoes_.clear();
  for (const auto& [key, p] : pairs_) {
    if (Echo(p, /*b_is_later=*/true)) echoes_.push_back(key.second);
    if (Echo(p, /*b_is_later=*/false)) echoes_.push_back(key.first);
  }
  ++frame_;
}

bool EchoWatch::Echo(const Pair& p, bool b_is_later) const {
  if (p.frames < options_.min_frames || p.envelope_frames < options_.min_frames) return false;
  const double later_share = b_is_later ? p.b_share : 1.0 - p.b_share;
  const bool independent = b_is_later ? p.b_independent : p.a_independent;
  return later_share < 0.5 && !independent && p.EnvelopeCorrelation() >= options_.min_envelope_correlation &&
         Best(b_is_later ? p.b_lags : p.a_lags).first >= options_.min_rho;
}

bool EchoWatch::IsEcho(uint64_t id) const { return std::find(echoes_.begin(), echoes_.end(), id) != echoes_.end(); }

bool EchoWatch::View(uint64_t earlier, uint64_t later, PairView* out) const {
  const bool b_is_later = earlier < later;
  const auto it = pairs_.find(b_is_later ? std::make_pair(earlier, later) : std::make_pair(later, earlier));
  if (it == pairs_.end()) return false;
  const Pair& p = it->second;
  const auto [rho, lag] = Best(b_is_later ? p.b_lags : p.a_lags);
  out->frames = p.frames;
  out->best_rho = rho;
  out->best_lag = lag;
  out->power_share = b_is_later ? p.b_share : 1.0 - p.b_share;
  out->envelope_correlation = p.EnvelopeCorrelation();
  out->later_independent = b_is_later ? p.b_independent : p.a_independent;
  return true;
}

}  // namespace localizer::engine
