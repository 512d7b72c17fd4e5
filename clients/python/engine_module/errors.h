// Engine Status -> Python exception, in one place: INVALID_ARGUMENT (the caller's input is
// malformed) is ValueError, every other code RuntimeError; the message is the engine's, with
// its code name in front so that a RuntimeError still says which kind it was.
#pragma once

#include <pybind11/pybind11.h>

#include <string>

#include "engine/core/status.h"

namespace localizer::python {

// Throws (pybind11 turns the C++ exception into the Python one) unless `status` is OK.
void ThrowIfError(const Status& status);

template <typename T>
T ValueOrThrow(StatusOr<T> result) {
  ThrowIfError(result.status());
  return std::move(result).value();
}

// A ValueError for input the bindings refuse before the engine sees it (shape, dtype).
[[noreturn]] void ThrowValueError(const std::string& message);

}  // namespace localizer::python
