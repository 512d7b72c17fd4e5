// GCC-PHAT (engine/tdoa/gcc_phat.h) for one pair of channels and for an array's frame,
// multilateration (engine/array/multilateration.h) and the TDOA model of an array.
// Sign convention throughout (engine/core/measurement.h): delay = t_arrival(other sensor) -
// t_arrival(reference), positive when the source is nearer the reference.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include "clients/python/engine_module/bindings.h"
#include "clients/python/engine_module/errors.h"
#include "clients/python/engine_module/numpy_convert.h"
#include "engine/array/array_geometry.h"
#include "engine/array/multilateration.h"
#include "engine/tdoa/gcc_phat.h"

namespace localizer::python {

namespace {

engine::GccOptions GccOptionsFrom(int frame_samples, double sample_rate_hz, const std::string& weighting,
                                  double phat_beta, double band_low_hz, double band_high_hz) {
  engine::GccOptions options;
  options.frame_samples = frame_samples;
  options.sample_rate_hz = sample_rate_hz;
  options.weighting = ValueOrThrow(engine::ParseWeighting(weighting));
  options.phat_beta = phat_beta;
  options.band_low_hz = band_low_hz;
  options.band_high_hz = band_high_hz;
  options.keep_gcc = false;  // only the peaks are returned
  return options;
}

// Runs one frame (channel-major) through a fresh estimator, without the GIL.
engine::Measurement MeasureFrame(const engine::ArrayGeometry& array, const engine::GccOptions& options,
                                 const float* frame) {
  StatusOr<std::unique_ptr<engine::GccPhatEstimator>> estimator = Status(StatusCode::kInternal, "not created");
  engine::Measurement measurement;
  Status status;
  {
    py::gil_scoped_release release;
    estimator = engine::GccPhatEstimator::Create(array, options);
    if (estimator.ok()) status = (*estimator)->Estimate(frame, options.frame_samples, 0.0, &measurement);
  }
  ThrowIfError(estimator.status());
  ThrowIfError(status);
  return measurement;
}

int FrameLength(int64_t samples, const std::string& name) {
  if (samples < 1 || samples > (int64_t{1} << 20)) {
    ThrowValueError(name + ": " + std::to_string(samples) + " samples per channel, expected 64 to 2^20");
  }
  return static_cast<int>(samples);
}

py::dict PairDict(const engine::PairMeasurement& p, double sample_rate_hz) {
  py::dict out;
  out["delay_s"] = p.delay_s;
  out["delay_samples"] = p.delay_s * sample_rate_hz;
  out["quality"] = p.quality;
  out["peak_value"] = p.peak_value;
  out["peak_snr"] = p.peak_snr;
  out["delay_sigma_s"] = p.delay_sigma_s;
  return out;
}

// The engine's estimator measures arrays of 4 or more sensors off a plane. A pair is measured
// as pair 0 of a stand-in tetrahedron with unit edges from the reference and the sound speed
// 1 / max_delay_s, so that its delay bound (which sets the searched lag window) is
// max_delay_s; the two other channels repeat the reference and are ignored.
py::dict GccPhatPair(const py::handle& reference, const py::handle& other, double sample_rate_hz, double max_delay_s,
                     const std::string& weighting, double phat_beta, double band_low_hz, double band_high_hz) {
  const auto x_ref = ChannelFrom(reference, "reference");
  const auto x_other = ChannelFrom(other, "other");
  if (x_ref.size() != x_other.size()) {
    ThrowValueError("reference has " + std::to_string(x_ref.size()) + " samples, other " +
                    std::to_string(x_other.size()) + "; a pair's channels must be as long");
  }
  if (!(max_delay_s > 0.0) || !std::isfinite(max_delay_s)) {
    ThrowValueError("max_delay_s is " + std::to_string(max_delay_s) + ", must be > 0 and finite");
  }
  const int n = FrameLength(x_ref.size(), "reference");
  const engine::ArrayGeometry array = ValueOrThrow(engine::ArrayGeometry::Create(
      {engine::Vec3::Zero(), engine::Vec3::UnitX(), engine::Vec3::UnitY(), engine::Vec3::UnitZ()}, 1.0 / max_delay_s));
  std::vector<float> frame(4 * static_cast<size_t>(n));
  for (int c = 0; c < 4; ++c) {
    const float* from = c == 1 ? x_other.data() : x_ref.data();
    std::copy(from, from + n, frame.begin() + static_cast<std::ptrdiff_t>(c) * n);
  }
  const engine::GccOptions options = GccOptionsFrom(n, sample_rate_hz, weighting, phat_beta, band_low_hz, band_high_hz);
  const engine::Measurement measurement = MeasureFrame(array, options, frame.data());
  return PairDict(measurement.pairs.at(0), sample_rate_hz);
}

py::array GccPhatArray(const py::handle& frame_value, const py::handle& sensors_m, double sample_rate_hz,
                       double sound_speed_mps, int reference_sensor, const std::string& weighting, double phat_beta,
                       double band_low_hz, double band_high_hz) {
  const ChannelMajorBlock frame = BlockFrom(frame_value, "frame");
  const engine::ArrayGeometry array = ValueOrThrow(
      engine::ArrayGeometry::Create(PositionsFrom(sensors_m, "sensors_m"), sound_speed_mps, reference_sensor));
  if (frame.channel_count != array.sensor_count()) {
    ThrowValueError("frame has " + std::to_string(frame.channel_count) + " channels, the array " +
                    std::to_string(array.sensor_count()) + " sensors (channel k = sensor k)");
  }
  const int n = FrameLength(frame.samples_per_channel, "frame");
  const engine::GccOptions options = GccOptionsFrom(n, sample_rate_hz, weighting, phat_beta, band_low_hz, band_high_hz);
  const engine::Measurement measurement = MeasureFrame(array, options, frame.samples());
  RecordWriter out(RecordDtype({{"sensor", "<i4", {}},
                                {"delay_s", "<f8", {}},
                                {"delay_samples", "<f8", {}},
                                {"quality", "<f8", {}},
                                {"peak_value", "<f8", {}},
                                {"peak_snr", "<f8", {}},
                                {"delay_sigma_s", "<f8", {}}}),
                   measurement.pairs.size());
  const size_t sensor_at = out.Offset("sensor"), delay_at = out.Offset("delay_s");
  const size_t samples_at = out.Offset("delay_samples"), quality_at = out.Offset("quality");
  const size_t peak_at = out.Offset("peak_value"), snr_at = out.Offset("peak_snr");
  const size_t sigma_at = out.Offset("delay_sigma_s");
  for (size_t row = 0; row < measurement.pairs.size(); ++row) {
    const engine::PairMeasurement& p = measurement.pairs[row];
    out.Set<int32_t>(row, sensor_at, p.sensor);
    out.Set<double>(row, delay_at, p.delay_s);
    out.Set<double>(row, samples_at, p.delay_s * sample_rate_hz);
    out.Set<double>(row, quality_at, p.quality);
    out.Set<double>(row, peak_at, p.peak_value);
    out.Set<double>(row, snr_at, p.peak_snr);
    out.Set<double>(row, sigma_at, p.delay_sigma_s);
  }
  return out.array();
}

py::array ToNumpy(const Eigen::VectorXd& v) {
  py::array_t<double> out(v.size());
  std::copy(v.data(), v.data() + v.size(), out.mutable_data());
  return out;
}

py::array ToNumpy(const engine::Mat3& m) {
  py::array_t<double> out({3, 3});
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) out.mutable_at(r, c) = m(r, c);
  return out;
}

py::dict Multilaterate(const py::handle& sensors_m, const py::handle& tdoa_value, double sound_speed_mps,
                       int reference_sensor, double tdoa_sigma_s, int max_iterations, const py::object& hint) {
  const engine::ArrayGeometry array = ValueOrThrow(
      engine::ArrayGeometry::Create(PositionsFrom(sensors_m, "sensors_m"), sound_speed_mps, reference_sensor));
  const std::vector<double> tdoa = DoublesFrom(tdoa_value, "tdoa_s");
  engine::MultilaterationOptions options;
  options.tdoa_sigma_s = tdoa_sigma_s;
  options.max_iterations = max_iterations;
  engine::Vec3 hint_m;
  if (!hint.is_none()) {
    hint_m = Vec3From(hint, "hint_m");
    options.hint_m = &hint_m;
  }
  if (!(tdoa_sigma_s > 0.0) || !std::isfinite(tdoa_sigma_s)) ThrowValueError("tdoa_sigma_s must be > 0 and finite");
  if (max_iterations < 1) ThrowValueError("max_iterations must be >= 1");
  StatusOr<engine::Fix> fix = Status(StatusCode::kInternal, "not computed");
  {
    py::gil_scoped_release release;
    fix = engine::Multilaterate(
        array, Eigen::Map<const Eigen::VectorXd>(tdoa.data(), static_cast<Eigen::Index>(tdoa.size())), options);
  }
  ThrowIfError(fix.status());
  py::dict out;
  out["position_m"] = ToNumpy(Eigen::VectorXd(fix->position_m));
  out["covariance_m2"] = ToNumpy(fix->covariance_m2);
  out["position_std_m"] = fix->position_std_m();
  out["rms_residual_s"] = fix->rms_residual_s;
  out["iterations"] = fix->iterations;
  out["converged"] = fix->converged;
  return out;
}

py::array ModelTdoa(const py::handle& sensors_m, const py::handle& source_m, double sound_speed_mps,
                    int reference_sensor) {
  const engine::ArrayGeometry array = ValueOrThrow(
      engine::ArrayGeometry::Create(PositionsFrom(sensors_m, "sensors_m"), sound_speed_mps, reference_sensor));
  const engine::Vec3 source = Vec3From(source_m, "source_m");
  if (!source.allFinite()) ThrowValueError("source_m must be finite");
  return ToNumpy(array.Tdoa(source));
}

}  // namespace

void RegisterTdoa(py::module_& m) {
  const engine::GccOptions gcc;
  m.def("gcc_phat_pair", &GccPhatPair, py::arg("reference"), py::arg("other"), py::arg("sample_rate_hz"),
        py::arg("max_delay_s"), py::kw_only(), py::arg("weighting") = "phat", py::arg("phat_beta") = gcc.phat_beta,
        py::arg("band_low_hz") = 0.0, py::arg("band_high_hz") = 0.0,
        "The delay of `other` behind `reference` (two 1-D arrays of one length, 64..2^20 samples) searched "
        "within +-max_delay_s: dict delay_s, delay_samples, quality, peak_value, peak_snr, delay_sigma_s.");
  m.def("gcc_phat", &GccPhatArray, py::arg("frame"), py::arg("sensors_m"), py::arg("sample_rate_hz"), py::kw_only(),
        py::arg("sound_speed_mps") = 1500.0, py::arg("reference_sensor") = 0, py::arg("weighting") = "phat",
        py::arg("phat_beta") = gcc.phat_beta, py::arg("band_low_hz") = 0.0, py::arg("band_high_hz") = 0.0,
        "Every pair (reference, k) of one frame (samples, channels): a structured array, one row per pair.");
  m.def("multilaterate", &Multilaterate, py::arg("sensors_m"), py::arg("tdoa_s"), py::kw_only(),
        py::arg("sound_speed_mps") = 1500.0, py::arg("reference_sensor") = 0,
        py::arg("tdoa_sigma_s") = engine::MultilaterationOptions{}.tdoa_sigma_s,
        py::arg("max_iterations") = engine::MultilaterationOptions{}.max_iterations, py::arg("hint_m") = py::none(),
        "A position from one TDOA per pair (reference, k), k ascending: dict position_m, covariance_m2, ...");
  m.def("model_tdoa", &ModelTdoa, py::arg("sensors_m"), py::arg("source_m"), py::kw_only(),
        py::arg("sound_speed_mps") = 1500.0, py::arg("reference_sensor") = 0,
        "The TDOA per pair (reference, k) of a source at source_m, seconds (the engine's model).");
}

}  // namespace localizer::python
