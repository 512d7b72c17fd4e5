// localizer.engine.TwsTracker: the track-while-scan multi-target tracker (engine/tws/
// tws_tracker.h): scans of plots in, tracks with stable ids out.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <memory>
#include <string>
#include <vector>

#include "clients/python/engine_module/bindings.h"
#include "clients/python/engine_module/errors.h"
#include "clients/python/engine_module/numpy_convert.h"
#include "engine/tws/tws_tracker.h"

namespace localizer::python {

namespace {

using engine::tws::TwsOptions;

// The numeric options by their names in tws_options.h (the polar noise's without "noise.").
void SetOption(TwsOptions& o, const std::string& name, const py::handle& v) {
  const auto d = [&] { return v.cast<double>(); };
  const auto i = [&] { return v.cast<int>(); };
  if (name == "dimensions")
    o.dimensions = i();
  else if (name == "range_sigma_m")
    o.noise.range_sigma_m = d();
  else if (name == "bearing_sigma_rad")
    o.noise.bearing_sigma_rad = d();
  else if (name == "elevation_sigma_rad")
    o.noise.elevation_sigma_rad = d();
  else if (name == "accel_noise_mps2")
    o.accel_noise_mps2 = d();
  else if (name == "gate_probability")
    o.gate_probability = d();
  else if (name == "confirm_hits")
    o.confirm_hits = i();
  else if (name == "confirm_window")
    o.confirm_window = i();
  else if (name == "max_coast_scans")
    o.max_coast_scans = i();
  else if (name == "max_position_sigma_m")
    o.max_position_sigma_m = d();
  else if (name == "initial_speed_sigma_mps")
    o.initial_speed_sigma_mps = d();
  else if (name == "max_speed_mps")
    o.max_speed_mps = d();
  else if (name == "max_tracks")
    o.max_tracks = i();
  else
    throw py::type_error("TwsTracker: unknown option '" + name + "'");
}

py::dict SummaryDict(const engine::tws::ScanSummary& s) {
  py::dict out;
  out["plots"] = s.plots;
  out["assigned"] = s.assigned;
  out["initiated"] = s.initiated;
  out["deleted"] = s.deleted;
  out["confirmed"] = s.confirmed;
  out["tentative"] = s.tentative;
  return out;
}

class PyTwsTracker {
 public:
  explicit PyTwsTracker(const py::kwargs& options) {
    TwsOptions o;
    for (const auto& [key, value] : options) SetOption(o, py::str(key), value);
    tracker_ = ValueOrThrow(engine::tws::TwsTracker::Create(o));
  }

  // Polar plots from a sensor at sensor_position_m; elevation_rad None: 2-D plots.
  py::dict ProcessScan(double time_s, const py::handle& range_value, const py::handle& bearing_value,
                       const py::object& elevation_value, const py::handle& sensor_position) {
    const std::vector<double> range = DoublesFrom(range_value, "range_m");
    const std::vector<double> bearing = DoublesFrom(bearing_value, "bearing_rad");
    if (bearing.size() != range.size()) ThrowValueError("range_m and bearing_rad must be as long");
    std::vector<double> elevation;
    if (!elevation_value.is_none()) {
      elevation = DoublesFrom(elevation_value, "elevation_rad");
      if (elevation.size() != range.size()) ThrowValueError("elevation_rad must be as long as range_m");
    }
    engine::Scan scan;
    scan.time_s = time_s;
    scan.sensor_position_m = Vec3From(sensor_position, "sensor_position_m");
    for (size_t k = 0; k < range.size(); ++k) {
      engine::Detection d;
      d.range_m = range[k];
      d.bearing_rad = bearing[k];
      if (!elevation.empty()) d.elevation_rad = elevation[k];
      scan.detections.push_back(d);
    }
    engine::tws::ScanSummary summary;
    Status status;
    {
      py::gil_scoped_release release;
      status = tracker_->Process(scan, &summary);
    }
    ThrowIfError(status);
    return SummaryDict(summary);
  }

  // Cartesian plots: positions (N, 3) m with covariances (N, 3, 3) m^2.
  py::dict ProcessCartesian(double time_s, const py::handle& positions_value, const py::handle& covariances_value) {
    const std::vector<engine::Vec3> positions = PositionsFrom(positions_value, "positions_m");
    const auto covariances = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(covariances_value);
    if (!covariances) throw py::error_already_set();
    if (covariances.ndim() != 3 || covariances.shape(0) != static_cast<py::ssize_t>(positions.size()) ||
        covariances.shape(1) != 3 || covariances.shape(2) != 3) {
      ThrowValueError("covariances_m2: expected shape (" + std::to_string(positions.size()) + ", 3, 3)");
    }
    std::vector<engine::tws::CartesianPlot> plots(positions.size());
    for (size_t k = 0; k < positions.size(); ++k) {
      plots[k].position_m = positions[k];
      for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c) plots[k].covariance_m2(r, c) = covariances.at(static_cast<py::ssize_t>(k), r, c);
    }
    engine::tws::ScanSummary summary;
    Status status;
    {
      py::gil_scoped_release release;
      status = tracker_->ProcessCartesian(time_s, plots, &summary);
    }
    ThrowIfError(status);
    return SummaryDict(summary);
  }

  py::array Tracks(bool include_tentative) const {
    const std::vector<engine::tws::TrackReport> tracks = tracker_->Tracks(include_tentative);
    RecordWriter out(RecordDtype({{"id", "<u8", {}},
                                  {"status", "<U10", {}},
                                  {"position_m", "<f8", {3}},
                                  {"velocity_mps", "<f8", {3}},
                                  {"covariance", "<f8", {6, 6}},
                                  {"hits", "<i4", {}},
                                  {"consecutive_misses", "<i4", {}},
                                  {"time_s", "<f8", {}}}),
                     tracks.size());
    const size_t id_at = out.Offset("id"), status_at = out.Offset("status"), p_at = out.Offset("position_m");
    const size_t v_at = out.Offset("velocity_mps"), cov_at = out.Offset("covariance"), hits_at = out.Offset("hits");
    const size_t misses_at = out.Offset("consecutive_misses"), time_at = out.Offset("time_s");
    for (size_t row = 0; row < tracks.size(); ++row) {
      const engine::tws::TrackReport& t = tracks[row];
      out.Set<uint64_t>(row, id_at, t.id);
      const std::string status = engine::TrackStatusName(t.status);
      for (size_t k = 0; k < status.size() && k < 10; ++k) {
        out.Set<uint32_t>(row, status_at + 4 * k, static_cast<uint32_t>(status[k]));  // numpy "U": UCS-4
      }
      out.SetMany(row, p_at, t.position_m.data(), 3);
      out.SetMany(row, v_at, t.velocity_mps.data(), 3);
      const Eigen::Matrix<double, 6, 6, Eigen::RowMajor> covariance = t.covariance;
      out.SetMany(row, cov_at, covariance.data(), 36);
      out.Set<int32_t>(row, hits_at, t.hits);
      out.Set<int32_t>(row, misses_at, t.consecutive_misses);
      out.Set<double>(row, time_at, t.time_s);
    }
    return out.array();
  }

 private:
  std::unique_ptr<engine::tws::TwsTracker> tracker_;
};

}  // namespace

void RegisterTws(py::module_& m) {
  py::class_<PyTwsTracker>(m, "TwsTracker",
                           "Track-while-scan multi-target tracker (engine::tws::TwsTracker): plots in, tracks "
                           "with stable ids out.")
      .def(py::init<const py::kwargs&>())
      .def("process_scan", &PyTwsTracker::ProcessScan, py::arg("time_s"), py::arg("range_m"), py::arg("bearing_rad"),
           py::arg("elevation_rad") = py::none(), py::arg("sensor_position_m") = py::make_tuple(0.0, 0.0, 0.0))
      .def("process_cartesian", &PyTwsTracker::ProcessCartesian, py::arg("time_s"), py::arg("positions_m"),
           py::arg("covariances_m2"))
      .def("tracks", &PyTwsTracker::Tracks, py::arg("include_tentative") = true);
}

}  // namespace localizer::python
