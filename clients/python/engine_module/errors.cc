#include "clients/python/engine_module/errors.h"

namespace localizer::python {

void ThrowIfError(const Status& status) {
  if (status.ok()) return;
  if (status.code() == StatusCode::kInvalidArgument) throw pybind11::value_error(status.message());
  throw std::runtime_error(status.ToString());  // pybind11 maps std::runtime_error to RuntimeError
}

void ThrowValueError(const std::string& message) { throw pybind11::value_error(message); }

}  // namespace localizer::python
