// Acquisition::EarlierArrival (acquisition.h): one channel's earlier arrival, seen by every
// pair that holds that channel, where no other channel has one.
#include <algorithm>
#include <cmath>

#include "engine/acquisition/acquisition.h"

namespace localizer::engine {
namespace {

// Every pair's value there, and the excess of their sum over its mirror image in units of the
// sum's noise-only spread (sqrt of the pairs): a peak, not noise.
constexpr double kMinArrivalValue = 3.0;

}  // namespace

bool Acquisition::EarlierArrival(const Vec3& at_m, std::vector<double>* reference_lags) const {
  // An echo whose extra path is about the same at every sensor (a far reflector, a compact
  // array) puts a cross term at every pair's lag minus that delay: every channel then seems to
  // have an earlier arrival, and none of them is the direct path. One channel alone is the
  // anomaly of a louder echo.
  int found = 0;
  std::vector<double> lags;
  for (int s = 0; s < array_.sensor_count() && found < 2; ++s) {
    if (ChannelEarlierArrival(at_m, s, &lags)) {
      ++found;
      *reference_lags = lags;
    }
  }
  return found == 1;
}

bool Acquisition::ChannelEarlierArrival(const Vec3& at_m, int sensor, std::vector<double>* reference_lags) const {
  const double fs = field_.sample_rate_hz();
  const int pairs = field_.reference_pairs();
  const int ref = array_.reference_sensor();
  const Eigen::VectorXd lags = array_.Tdoa(at_m) * fs;
  // The field pairs holding `sensor`, each with its lag at at_m and the sign by which its lag
  // moves when the sensor's arrival moves by +1 sample (pair (a, b) reads t_b - t_a).
  struct Involved {
    int pair;
    double lag;
    double sign;
  };
  std::vector<Involved> involved;
  int cross = 0;
  for (int q = 0; q < field_.pair_count(); ++q) {
    if (!field_.usable(q)) continue;
    const int a = q < pairs ? ref : field_.cross_sensor_a(q);
    const int b = q < pairs ? array_.sensor_of_pair(q) : field_.cross_sensor_b(q);
    if (a != sensor && b != sensor) continue;
    involved.push_back({q, q < pairs ? lags(q) : CrossLag(q, lags), b == sensor ? 1.0 : -1.0});
    cross += q >= pairs;
  }
  // Without a pair beyond the reference pairs nothing can confirm a shift: it would move one
  // pair's lag alone (or, for the reference sensor, all of them alike).
  if (cross == 0 || involved.size() < 2) return false;
  int widest = 0;
  for (const Involved& v : involved) widest = std::max(widest, field_.last_lag(v.pair) - field_.first_lag(v.pair));
  const auto sum_at = [&](int shift) {
    double s = 0.0;
    for (const Involved& v : involved) s += field_.At(v.pair, v.lag + v.sign * shift);
    return s;
  };
  // Out of the main lobe first: up to its top (the position's lags may sit on its flank),
  // then down while the sum falls.
  int shift = 0;
  double previous = sum_at(0);
  // Steps earlier while the next sum keeps `previous` in order (rising, then falling).
  const auto walk = [&](auto keeps_on) {
    for (; shift > -widest; --shift) {
      const double next = sum_at(shift - 1);
      if (!keeps_on(next)) return;
      previous = next;
    }
  };
  walk([&](double next) { return next >= previous; });
  const int top = shift;
  walk([&](double next) { return next <= previous; });
  // A source's own GCC is symmetric about its peak (the whitened spectrum's autocorrelation):
  // a sidelobe, or an echo's cross term delayed alike at every sensor, reads as high on the
  // later side as on the earlier one. An earlier arrival reads above its mirror image.
  const auto excess_at = [&](int earlier) { return sum_at(earlier) - sum_at(2 * top - earlier); };
  int best_shift = 0;
  double best = -1e300;
  for (; shift >= -widest; --shift) {
    const double now = excess_at(shift);
    if (now > best) {
      best = now;
      best_shift = shift;
    }
  }
  if (best_shift == 0 || best < kMinArrivalValue * std::sqrt(static_cast<double>(involved.size()))) return false;
  for (const Involved& v : involved) {
    if (field_.At(v.pair, v.lag + v.sign * best_shift) < kMinArrivalValue) return false;
  }
  reference_lags->assign(static_cast<size_t>(pairs), 0.0);
  for (int p = 0; p < pairs; ++p) {
    const int b = array_.sensor_of_pair(p);
    (*reference_lags)[static_cast<size_t>(p)] =
        lags(p) + (b == sensor ? best_shift : 0.0) - (ref == sensor ? best_shift : 0.0);
  }
  return true;
}

}  // namespace localizer::engine
