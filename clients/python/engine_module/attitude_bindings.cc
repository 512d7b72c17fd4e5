// localizer.engine.AttitudeFilter: the platform attitude filter (engine/attitude/
// attitude_filter.h) over batches of IMU samples, one estimate per sample.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <cmath>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "clients/python/engine_module/bindings.h"
#include "clients/python/engine_module/errors.h"
#include "clients/python/engine_module/numpy_convert.h"
#include "engine/attitude/attitude_filter.h"

namespace localizer::python {

namespace {

using engine::AttitudeFilterOptions;

// (N, 3) float64, C order.
py::array_t<double, py::array::c_style | py::array::forcecast> Rows3(const py::handle& value, const std::string& name,
                                                                     py::ssize_t rows) {
  auto array = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(value);
  if (!array) throw py::error_already_set();
  if (array.ndim() != 2 || array.shape(0) != rows || array.shape(1) != 3) {
    ThrowValueError(name + ": expected shape (" + std::to_string(rows) + ", 3), one row per sample");
  }
  return array;
}

class PyAttitudeFilter {
 public:
  PyAttitudeFilter(const std::string& kind, bool use_mag, const py::kwargs& options) {
    options_.kind = ValueOrThrow(engine::ParseAttitudeFilterKind(kind));
    options_.use_mag = use_mag;
    for (const auto& [key, value] : options) {
      const std::string name = py::str(key);
      bool known = false;
      for (const auto& [option, member] : engine::AttitudeNumericOptions()) {
        if (name != option) continue;
        options_.*member = value.cast<double>();
        known = true;
      }
      if (!known) throw py::type_error("AttitudeFilter: unknown option '" + name + "'");
    }
    filter_ = ValueOrThrow(engine::CreateAttitudeFilter(options_));
  }

  // All samples are checked before the first is applied: a bad batch changes nothing.
  py::array Update(const py::handle& t_value, const py::handle& gyro_value, const py::handle& accel_value,
                   const py::object& mag_value) {
    const std::vector<double> t_s = DoublesFrom(t_value, "t_s");
    const auto rows = static_cast<py::ssize_t>(t_s.size());
    const auto gyro = Rows3(gyro_value, "gyro_rps", rows);
    const auto accel = Rows3(accel_value, "accel_mps2", rows);
    std::vector<engine::ImuSample> samples(t_s.size());
    double previous_t_s = last_t_s_;
    for (py::ssize_t i = 0; i < rows; ++i) {
      engine::ImuSample& s = samples[static_cast<size_t>(i)];
      s.t_s = t_s[static_cast<size_t>(i)];
      s.gyro_rps = {gyro.at(i, 0), gyro.at(i, 1), gyro.at(i, 2)};
      s.accel_mps2 = {accel.at(i, 0), accel.at(i, 1), accel.at(i, 2)};
      ThrowIfError(engine::ValidateImuSample(s, previous_t_s));
      previous_t_s = s.t_s;
    }
    if (!mag_value.is_none()) {
      const auto mag = Rows3(mag_value, "mag_uT", rows);
      for (py::ssize_t i = 0; i < rows; ++i) {
        samples[static_cast<size_t>(i)].mag_uT = {mag.at(i, 0), mag.at(i, 1), mag.at(i, 2)};
      }
    }
    std::vector<engine::AttitudeEstimate> estimates;
    Status status;
    {
      py::gil_scoped_release release;
      for (const engine::ImuSample& s : samples) {
        status = filter_->Update(s);
        if (!status.ok()) break;
        estimates.push_back(filter_->estimate());
        last_t_s_ = s.t_s;
      }
    }
    ThrowIfError(status);
    return ToArray(estimates);
  }

 private:
  static py::array ToArray(const std::vector<engine::AttitudeEstimate>& estimates) {
    RecordWriter out(RecordDtype({{"t_s", "<f8", {}},
                                  {"quaternion", "<f8", {4}},  // body -> world (w, x, y, z)
                                  {"euler_rad", "<f8", {3}},   // roll, pitch, yaw (z-y'-x'')
                                  {"sd_rad", "<f8", {3}},
                                  {"gyro_bias_rps", "<f8", {3}},
                                  {"initialised", "?", {}},
                                  {"accel_used", "?", {}},
                                  {"mag_used", "?", {}},
                                  {"at_rest", "?", {}}}),
                     estimates.size());
    const size_t t_at = out.Offset("t_s"), q_at = out.Offset("quaternion"), euler_at = out.Offset("euler_rad");
    const size_t sd_at = out.Offset("sd_rad"), bias_at = out.Offset("gyro_bias_rps");
    const size_t init_at = out.Offset("initialised"), accel_at = out.Offset("accel_used");
    const size_t mag_at = out.Offset("mag_used"), rest_at = out.Offset("at_rest");
    for (size_t row = 0; row < estimates.size(); ++row) {
      const engine::AttitudeEstimate& e = estimates[row];
      const double q[4] = {e.body_to_world.w(), e.body_to_world.x(), e.body_to_world.y(), e.body_to_world.z()};
      out.Set<double>(row, t_at, e.t_s);
      out.SetMany(row, q_at, q, 4);
      out.SetMany(row, euler_at, e.euler_rad.data(), 3);
      out.SetMany(row, sd_at, e.sd_rad.data(), 3);
      out.SetMany(row, bias_at, e.gyro_bias_rps.data(), 3);
      out.Set<bool>(row, init_at, e.initialised);
      out.Set<bool>(row, accel_at, e.accel_used);
      out.Set<bool>(row, mag_at, e.mag_used);
      out.Set<bool>(row, rest_at, e.at_rest);
    }
    return out.array();
  }

  AttitudeFilterOptions options_;
  std::unique_ptr<engine::AttitudeFilter> filter_;
  double last_t_s_ = -std::numeric_limits<double>::infinity();
};

}  // namespace

void RegisterAttitude(py::module_& m) {
  py::class_<PyAttitudeFilter>(m, "AttitudeFilter",
                               "The platform attitude filter (engine::AttitudeFilter): IMU samples in, "
                               "body -> world quaternions out. kind: quaternion | euler.")
      .def(py::init<const std::string&, bool, const py::kwargs&>(), py::arg("kind") = "quaternion",
           py::arg("use_mag") = false)
      .def("update", &PyAttitudeFilter::Update, py::arg("t_s"), py::arg("gyro_rps"), py::arg("accel_mps2"),
           py::arg("mag_uT") = py::none(),
           "N samples (t_s (N,), gyro_rps (N, 3), accel_mps2 (N, 3), mag_uT (N, 3) or None) -> a structured "
           "array, one estimate per sample.");
}

}  // namespace localizer::python
