#include "engine/sim/random_scene.h"

#include <Eigen/Geometry>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <numbers>
#include <random>

#include "engine/sim/invalid_value.h"

namespace localizer::engine {
namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kMinApertureM = 0.2;
constexpr double kMaxApertureM = 40.0;
constexpr double kMaxAirApertureM = 5.0;  // larger microphone arrays are rare
constexpr double kMaxSpeedMps = 5.0;
constexpr double kNearestSensorApertures = 0.1;  // closest a track may pass a sensor
constexpr double kFarthestApertures = 10.0;      // farthest it may go from the centre
constexpr double kTrackCheckStepS = 0.1;

// Draws in a fixed order from one engine: the scene depends on the seed only.
class Draw {
 public:
  explicit Draw(uint64_t seed) {
    // A stream tag keeps scene draws apart from the simulator's streams of the same seed.
    std::seed_seq sequence{static_cast<uint32_t>(seed), static_cast<uint32_t>(seed >> 32), 0x5ce7e5u};
    engine_.seed(sequence);
  }
  double Uniform(double lo, double hi) { return std::uniform_real_distribution<double>(lo, hi)(engine_); }
  double LogUniform(double lo, double hi) { return std::exp(Uniform(std::log(lo), std::log(hi))); }
  int Integer(int lo, int hi) { return std::uniform_int_distribution<int>(lo, hi)(engine_); }
  bool Chance(double p) { return Uniform(0.0, 1.0) < p; }
  double Normal() { return std::normal_distribution<double>(0.0, 1.0)(engine_); }
  Vec3 UnitVector() {
    Vec3 v(Normal(), Normal(), Normal());
    while (v.norm() < 1e-9) v = Vec3(Normal(), Normal(), Normal());
    return v.normalized();
  }
  Mat3 Rotation() {  // uniform on SO(3): a normalised 4-D Gaussian as a quaternion
    Eigen::Quaterniond q(Normal(), Normal(), Normal(), Normal());
    if (q.norm() < 1e-9) q = Eigen::Quaterniond::Identity();
    return q.normalized().toRotationMatrix();
  }

 private:
  std::mt19937_64 engine_;
};

double Aperture(const std::vector<Vec3>& sensors) {
  double widest = 0.0;
  for (size_t i = 0; i < sensors.size(); ++i) {
    for (size_t j = i + 1; j < sensors.size(); ++j) widest = std::max(widest, (sensors[i] - sensors[j]).norm());
  }
  return widest;
}

double ClosestPair(const std::vector<Vec3>& sensors) {
  double closest = std::numeric_limits<double>::infinity();
  for (size_t i = 0; i < sensors.size(); ++i) {
    for (size_t j = i + 1; j < sensors.size(); ++j) closest = std::min(closest, (sensors[i] - sensors[j]).norm());
  }
  return closest;
}

// Thinnest over widest principal spread of the sensors about their centroid: 0 for a plane.
double Thickness(const std::vector<Vec3>& sensors) {
  Eigen::MatrixXd centred(static_cast<Eigen::Index>(sensors.size()), 3);
  Vec3 mean = Vec3::Zero();
  for (const Vec3& s : sensors) mean += s / static_cast<double>(sensors.size());
  for (size_t i = 0; i < sensors.size(); ++i)
    centred.row(static_cast<Eigen::Index>(i)) = (sensors[i] - mean).transpose();
  const Eigen::Vector3d sv = Eigen::JacobiSVD<Eigen::MatrixXd>(centred).singularValues();
  return sv(0) > 0.0 ? sv(2) / sv(0) : 0.0;
}

// Centred on the origin and scaled to the aperture exactly.
std::vector<Vec3> Normalised(std::vector<Vec3> sensors, double aperture_m) {
  Vec3 mean = Vec3::Zero();
  for (const Vec3& s : sensors) mean += s / static_cast<double>(sensors.size());
  const double scale = aperture_m / Aperture(sensors);
  for (Vec3& s : sensors) s = (s - mean) * scale;
  return sensors;
}

std::vector<Vec3> IrregularTetrahedron(Draw& draw, double aperture_m) {
  const std::vector<Vec3> regular = {Vec3(1, 1, 1), Vec3(1, -1, -1), Vec3(-1, 1, -1), Vec3(-1, -1, 1)};
  for (;;) {
    const Mat3 rotation = draw.Rotation();
    std::vector<Vec3> sensors;
    for (const Vec3& corner : regular) {
      const Vec3 jitter(draw.Uniform(-0.15, 0.15), draw.Uniform(-0.15, 0.15), draw.Uniform(-0.15, 0.15));
      sensors.push_back(rotation * (corner * aperture_m / (2.0 * std::numbers::sqrt2) + jitter * aperture_m));
    }
    if (Thickness(sensors) >= 0.2) return Normalised(sensors, aperture_m);
  }
}

std::vector<Vec3> SpreadArray(Draw& draw, int count, double aperture_m) {
  for (;;) {
    std::vector<Vec3> sensors;
    while (static_cast<int>(sensors.size()) < count) {
      const Vec3 p(draw.Uniform(-1, 1), draw.Uniform(-1, 1), draw.Uniform(-1, 1));
      if (p.norm() <= 1.0) sensors.push_back(0.5 * aperture_m * p);
    }
    if (ClosestPair(sensors) >= 0.15 * Aperture(sensors) && Thickness(sensors) >= 0.2) {
      return Normalised(sensors, aperture_m);
    }
  }
}

// Whether the track stays in the array's reach over the run.
bool TrackFits(const Trajectory& track, const std::vector<Vec3>& sensors, double aperture_m, double duration_s) {
  for (int k = 0; k * kTrackCheckStepS <= duration_s + 1e-9; ++k) {
    const Vec3 p = track.PositionAt(k * kTrackCheckStepS);
    if (p.norm() > kFarthestApertures * aperture_m) return false;
    for (const Vec3& s : sensors) {
      if ((p - s).norm() < kNearestSensorApertures * aperture_m) return false;
    }
  }
  return true;
}

// Lowest and highest z of the sensors and the track.
std::pair<double, double> VerticalExtent(const Trajectory& track, const std::vector<Vec3>& sensors, double duration_s) {
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  for (const Vec3& s : sensors) lo = std::min(lo, s.z()), hi = std::max(hi, s.z());
  for (int k = 0; k * kTrackCheckStepS <= duration_s + 1e-9; ++k) {
    const double z = track.PositionAt(k * kTrackCheckStepS).z();
    lo = std::min(lo, z), hi = std::max(hi, z);
  }
  return {lo, hi};
}

const char* SpectrumName(const SimOptions& o) {
  if (o.signal == SourceSignal::kTonalBroadband) return "tones+broadband";
  return o.band_low_hz == 0.0 ? "low-pass" : "broadband";
}

}  // namespace

const char* SceneClassName(SceneClass scene_class) {
  switch (scene_class) {
    case SceneClass::kGaussian:
      return "gaussian";
    case SceneClass::kMultipath:
      return "multipath";
    case SceneClass::kImpulsive:
      return "impulsive";
  }
  return "unknown";
}

StatusOr<SceneClass> ParseSceneClass(const std::string& name) {
  for (SceneClass c : {SceneClass::kGaussian, SceneClass::kMultipath, SceneClass::kImpulsive}) {
    if (name == SceneClassName(c)) return c;
  }
  return InvalidArgument("scene class '" + name + "' is unknown; valid: gaussian, multipath, impulsive");
}

StatusOr<RandomScene> DrawRandomScene(uint64_t seed, const RandomSceneOptions& options) {
  if (!(options.duration_s > 0.0) || !std::isfinite(options.duration_s)) {
    return sim_detail::Invalid("duration_s", options.duration_s, "must be positive and finite");
  }
  Draw draw(seed);
  RandomScene scene;
  scene.seed = seed;
  const auto drawn_class = static_cast<SceneClass>(draw.Integer(0, 2));
  scene.scene_class = options.scene_class.value_or(drawn_class);
  const double duration_s = options.duration_s;

  // Geometry.
  const double aperture_m = draw.LogUniform(kMinApertureM, kMaxApertureM);
  const bool tetrahedron = draw.Chance(0.5);
  const int sensor_count = tetrahedron ? 4 : draw.Integer(6, 8);
  std::vector<Vec3> sensors =
      tetrahedron ? IrregularTetrahedron(draw, aperture_m) : SpreadArray(draw, sensor_count, aperture_m);

  // Medium and sample rate.
  const bool air = aperture_m <= kMaxAirApertureM && draw.Chance(0.5);
  scene.medium = air ? "air" : "water";
  const double c = air ? 343.0 : 1500.0;
  SimOptions& o = scene.scenario.sim;
  o.seed = seed;
  o.duration_s = duration_s;
  o.truth_step_s = options.truth_step_s;
  o.sample_rate_hz = air ? (draw.Chance(0.5) ? 16000.0 : 48000.0) : (draw.Chance(0.5) ? 11025.0 : 16000.0);

  // Source start and motion, redrawn until the track stays in reach.
  Trajectory track;
  bool turning = false;
  for (int attempt = 0; attempt < 400; ++attempt) {
    const double speed_cap_mps = std::min(kMaxSpeedMps, 0.3 * c) * std::pow(0.8, attempt / 8);
    const double range_m = aperture_m * draw.LogUniform(0.3, 5.0);
    track.position_m = range_m * draw.UnitVector();
    const double speed_mps = draw.Uniform(0.0, speed_cap_mps);
    const double azimuth = draw.Uniform(0.0, 2.0 * kPi);
    const double elevation = draw.Uniform(-kPi / 9.0, kPi / 9.0);  // +-20 degrees
    track.velocity_mps = speed_mps * Vec3(std::cos(elevation) * std::cos(azimuth),
                                          std::cos(elevation) * std::sin(azimuth), std::sin(elevation));
    turning = draw.Chance(0.5);
    const double rate_radps = draw.Uniform(0.05, 0.5) * (draw.Chance(0.5) ? 1.0 : -1.0);
    track.turn_rate_radps = turning ? rate_radps : 0.0;
    if (TrackFits(track, sensors, aperture_m, duration_s)) break;
  }
  scene.start_range_m = track.position_m.norm();

  // Placement: water below the surface z = 0; air above a floor z = 0.
  const auto [z_lo, z_hi] = VerticalExtent(track, sensors, duration_s);
  const double shift_m = air ? draw.Uniform(0.3, 1.5) - z_lo : -(z_hi + 0.5 + draw.Uniform(0.0, aperture_m));
  for (Vec3& s : sensors) s.z() += shift_m;
  track.position_m.z() += shift_m;
  o.trajectory = track;
  const double scene_lo_m = z_lo + shift_m, scene_hi_m = z_hi + shift_m;

  // Noise and spectrum.
  o.snr_db = draw.Uniform(-5.0, 20.0);
  const double nyquist_hz = 0.5 * o.sample_rate_hz;
  const double high_max_hz = 0.8 * nyquist_hz;  // fractional delays are accurate below 0.4 fs
  const int spectrum = draw.Integer(0, 2);
  const double band_low_hz = draw.LogUniform(50.0, 0.3 * nyquist_hz);
  const double band_high_hz = draw.Uniform(std::min(2.0 * band_low_hz + 200.0, high_max_hz), high_max_hz);
  const double low_pass_high_hz = draw.LogUniform(500.0, high_max_hz);
  const double tone_fraction = draw.Uniform(0.3, 0.8);
  o.band_low_hz = spectrum == 1 ? 0.0 : band_low_hz;
  o.band_high_hz = spectrum == 1 ? low_pass_high_hz : band_high_hz;
  if (spectrum == 2) {
    o.signal = SourceSignal::kTonalBroadband;
    o.tone_count = 3;
    o.tone_power_fraction = tone_fraction;
  }

  // Class-specific parts, always drawn so that forcing a class changes only these.
  const double surface_r = air ? draw.Uniform(0.3, 0.8) : draw.Uniform(-0.95, -0.6);
  const double bottom_r = air ? draw.Uniform(0.3, 0.8) : draw.Uniform(0.2, 0.7);
  const bool upper_on = air ? draw.Chance(0.5) : true;  // ceiling (air) / surface (water)
  const bool lower_on = air ? true : draw.Chance(0.7);  // floor (air) / bottom (water)
  const double ceiling_gap_m = draw.Uniform(0.5, 2.0);
  const double bottom_gap_m = std::max(0.5, draw.Uniform(0.2, 2.0) * aperture_m);
  const double impulse_probability = draw.LogUniform(0.002, 0.02);
  const double impulse_scale = draw.Uniform(10.0, 50.0);
  const double impulse_alpha = draw.Uniform(1.2, 1.8);
  if (scene.scene_class == SceneClass::kMultipath) {
    o.surface_reflection_enabled = upper_on;
    o.surface_z_m = air ? scene_hi_m + ceiling_gap_m : 0.0;
    o.surface_reflection = surface_r;
    o.bottom_reflection_enabled = lower_on;
    o.bottom_z_m = air ? 0.0 : scene_lo_m - bottom_gap_m;
    o.bottom_reflection = bottom_r;
  } else if (scene.scene_class == SceneClass::kImpulsive) {
    o.impulse_probability = impulse_probability;
    o.impulse_scale_over_noise_std = impulse_scale;
    o.impulse_alpha = impulse_alpha;
  }

  scene.aperture_m = aperture_m;
  scene.scenario.name = "random-" + std::to_string(seed);
  scene.scenario.sensors_m = sensors;
  scene.scenario.sound_speed_mps = c;
  char text[400];
  std::snprintf(text, sizeof text,
                "%s, %s, %d sensors over %.2f m, %g Hz; source %.2f m away at %.2f m/s %s; %s %.0f-%.0f Hz; "
                "SNR %.1f dB%s%s%s",
                SceneClassName(scene.scene_class), scene.medium.c_str(), sensor_count, aperture_m, o.sample_rate_hz,
                scene.start_range_m, track.velocity_mps.norm(), turning ? "turning" : "straight", SpectrumName(o),
                o.band_low_hz, o.band_high_hz, o.snr_db, o.surface_reflection_enabled ? "; upper echo" : "",
                o.bottom_reflection_enabled ? "; lower echo" : "", o.impulse_probability > 0.0 ? "; impulses" : "");
  scene.scenario.description = text;
  LOCALIZER_RETURN_IF_ERROR(o.Validate());
  return scene;
}

}  // namespace localizer::engine
