// localizer.engine.Session: engine::Session on numpy blocks (engine/pipeline/session.h).
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <memory>
#include <mutex>
#include <vector>

#include "clients/python/engine_module/bindings.h"
#include "clients/python/engine_module/errors.h"
#include "clients/python/engine_module/estimate_arrays.h"
#include "clients/python/engine_module/numpy_convert.h"
#include "clients/python/engine_module/session_config.h"
#include "engine/pipeline/session.h"

namespace localizer::python {

namespace {

// One engine session and the sequence numbers of the blocks it was given. The engine runs
// without the GIL, so two Python threads could call into one session at once; the mutex
// serialises them (engine::Session is not thread-safe), while different sessions run in
// parallel.
class PySession {
 public:
  PySession(const py::handle& sensors_m, double sample_rate_hz, const py::kwargs& options)
      : config_(SessionConfigFrom(sensors_m, sample_rate_hz, options)) {
    StatusOr<std::unique_ptr<engine::Session>> made = Status(StatusCode::kInternal, "not created");
    {
      py::gil_scoped_release release;  // Create plans FFTs and sizes the tracker
      made = engine::Session::Create(config_);
    }
    ThrowIfError(made.status());
    session_ = std::move(*made);
    pair_count_ = session_->reports_sources() ? 0 : session_->sensor_count() - 1;
  }

  py::object Process(const py::handle& block_value, bool with_sources) {
    const ChannelMajorBlock block = BlockFrom(block_value, "block");
    std::vector<engine::Estimate> estimates;
    Status status;
    {
      py::gil_scoped_release release;
      std::lock_guard<std::mutex> lock(mutex_);
      engine::BlockView view;
      view.sequence = sequence_ + 1;  // the engine wants them increasing; a rejected block keeps none
      view.channel_count = block.channel_count;
      view.samples_per_channel = block.samples_per_channel;
      view.samples = block.samples();
      status = session_->Process(view, &estimates);
      if (status.ok()) sequence_ = view.sequence;
    }
    ThrowIfError(status);
    py::array frames = EstimatesToArray(estimates, pair_count_);
    if (!with_sources) return frames;
    return py::make_tuple(frames, SourcesToArray(estimates));
  }

  void Skip(int64_t samples_per_channel) {
    Status status;
    {
      py::gil_scoped_release release;
      std::lock_guard<std::mutex> lock(mutex_);
      status = session_->Skip(samples_per_channel);
    }
    ThrowIfError(status);
  }

  py::dict Config() const {
    py::dict config = SessionConfigToDict(session_->config());
    config["localization"] = engine::LocalizationName(session_->localization());  // auto resolved
    return config;
  }

  const engine::Session& session() const { return *session_; }
  int pair_count() const { return pair_count_; }
  uint64_t frames_processed() {
    std::lock_guard<std::mutex> lock(mutex_);
    return session_->frames_processed();
  }

 private:
  engine::AudioSessionConfig config_;
  std::unique_ptr<engine::Session> session_;
  std::mutex mutex_;
  uint64_t sequence_ = 0;
  int pair_count_ = 0;
};

}  // namespace

void RegisterSession(py::module_& m) {
  py::class_<PySession>(m, "Session",
                        "An audio tracking session (engine::Session): blocks of samples in, one estimate per "
                        "frame out. Options are keyword arguments (Session.default_options()).")
      .def(py::init<const py::handle&, double, const py::kwargs&>(), py::arg("sensors_m"), py::arg("sample_rate_hz"))
      .def("process", &PySession::Process, py::arg("block"), py::arg("with_sources") = false,
           "block: (samples, channels) float32/float64 -> a structured array, one row per completed frame "
           "(with_sources: (frames, sources)).")
      .def("skip", &PySession::Skip, py::arg("samples_per_channel"),
           "The stream lost this many samples per channel before the next block.")
      .def_property_readonly("config", &PySession::Config)
      .def_property_readonly("localization",
                             [](const PySession& s) { return engine::LocalizationName(s.session().localization()); })
      .def_property_readonly("reports_sources", [](const PySession& s) { return s.session().reports_sources(); })
      .def_property_readonly("backend", [](const PySession& s) { return s.session().backend(); })
      .def_property_readonly("sensor_count", [](const PySession& s) { return s.session().sensor_count(); })
      .def_property_readonly("pair_count", &PySession::pair_count)
      .def_property_readonly("frames_processed", &PySession::frames_processed)
      .def_property_readonly("estimate_dtype", [](const PySession& s) { return EstimateDtype(s.pair_count()); })
      .def_static("default_options", &DefaultSessionOptions);
  m.def("estimate_dtype", &EstimateDtype, py::arg("pair_count"));
  m.def("source_dtype", &SourceDtype);
}

}  // namespace localizer::python
