// numpy <-> engine types for the bindings: sensor positions, 3-vectors, sample blocks, and
// numpy structured arrays filled column by column. Every shape or dtype the engine cannot
// take is a ValueError naming the argument, raised before the engine runs.
#pragma once

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <cstring>
#include <optional>
#include <string>
#include <vector>

#include "engine/core/types.h"

namespace localizer::python {

namespace py = pybind11;

// An (N, 3) array-like of metres (any real dtype) -> N positions.
std::vector<engine::Vec3> PositionsFrom(const py::handle& value, const std::string& name);
// Three numbers (a sequence or a numpy array of 3).
engine::Vec3 Vec3From(const py::handle& value, const std::string& name);
// A 1-D array-like of real numbers -> float64 values.
std::vector<double> DoublesFrom(const py::handle& value, const std::string& name);

// A block of samples in the engine's layout: channel-major float32 (engine/core/block.h).
// Taken from a (samples, channels) array of a real floating dtype: an F-contiguous float32
// array already is channel-major (e.g. localizer.audio.read(...).T) and is used in place;
// anything else (interleaved C order, float64, strided views) is converted once by numpy.
struct ChannelMajorBlock {
  py::array_t<float, py::array::f_style | py::array::forcecast> storage;  // keeps the samples alive
  int channel_count = 0;
  int64_t samples_per_channel = 0;
  const float* samples() const { return storage.data(); }
};
ChannelMajorBlock BlockFrom(const py::handle& value, const std::string& name);

// A 1-D real array -> float32 samples (one channel of a pair).
py::array_t<float, py::array::c_style | py::array::forcecast> ChannelFrom(const py::handle& value,
                                                                          const std::string& name);

// A numpy structured array built from (name, format[, shape]) columns and written by field
// offset, so that a row costs a few stores, not a Python object per value.
struct Column {
  std::string name;
  std::string format;      // numpy type code: "<f8", "<i4", "<u8", "?", "U10"
  std::vector<int> shape;  // empty: a scalar field
};
py::dtype RecordDtype(const std::vector<Column>& columns);

class RecordWriter {
 public:
  RecordWriter(const py::dtype& dtype, size_t rows);  // zero-filled rows
  // Byte offset of field `name` within a row.
  size_t Offset(const std::string& name) const;
  template <typename T>
  void Set(size_t row, size_t offset, const T& value) {
    std::memcpy(data_ + row * itemsize_ + offset, &value, sizeof(T));
  }
  template <typename T>
  void SetMany(size_t row, size_t offset, const T* values, size_t count) {
    std::memcpy(data_ + row * itemsize_ + offset, values, sizeof(T) * count);
  }
  py::array array() const { return array_; }

 private:
  py::dtype dtype_;
  py::array array_;
  char* data_ = nullptr;
  size_t itemsize_ = 0;
};

}  // namespace localizer::python
