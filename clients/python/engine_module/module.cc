// localizer.engine: the engine in-process on numpy arrays (the Python package's compiled
// submodule). The stub clients/python/localizer/engine.pyi documents every name.
#include <pybind11/pybind11.h>

#include "clients/python/engine_module/bindings.h"
#include "engine/core/version.h"

PYBIND11_MODULE(engine, m) {
  m.doc() =
      "The localizer engine in-process: audio sessions, GCC-PHAT, multilateration, the simulator, "
      "the attitude filter and the track-while-scan tracker on numpy arrays. Engine errors raise "
      "ValueError (INVALID_ARGUMENT) or RuntimeError (any other code) with the engine's message.";
  m.attr("__version__") = localizer::kLocalizerVersion;
  localizer::python::RegisterSession(m);
  localizer::python::RegisterTdoa(m);
  localizer::python::RegisterSimulator(m);
  localizer::python::RegisterAttitude(m);
  localizer::python::RegisterTws(m);
}
