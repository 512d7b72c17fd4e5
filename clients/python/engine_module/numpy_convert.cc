#include "clients/python/engine_module/numpy_convert.h"

#include <pybind11/stl.h>

#include "clients/python/engine_module/errors.h"

namespace localizer::python {

namespace {

// np.asarray(value) with a real dtype (bool, int, float), else ValueError naming `name`.
py::array RealArray(const py::handle& value, const std::string& name) {
  py::array array = py::module_::import("numpy").attr("asarray")(value);
  const char kind = array.dtype().kind();
  if (kind != 'f' && kind != 'i' && kind != 'u') {
    ThrowValueError(name + ": dtype " + py::str(array.dtype()).cast<std::string>() + " is not a real number type");
  }
  return array;
}

std::string ShapeText(const py::array& array) { return py::str(array.attr("shape")).cast<std::string>(); }

}  // namespace

std::vector<engine::Vec3> PositionsFrom(const py::handle& value, const std::string& name) {
  const py::array_t<double, py::array::c_style | py::array::forcecast> positions(RealArray(value, name));
  if (positions.ndim() != 2 || positions.shape(1) != 3) {
    ThrowValueError(name + ": shape " + ShapeText(positions) + ", expected (sensors, 3) in metres");
  }
  std::vector<engine::Vec3> out;
  for (py::ssize_t i = 0; i < positions.shape(0); ++i) {
    out.emplace_back(positions.at(i, 0), positions.at(i, 1), positions.at(i, 2));
  }
  return out;
}

engine::Vec3 Vec3From(const py::handle& value, const std::string& name) {
  const std::vector<double> v = DoublesFrom(value, name);
  if (v.size() != 3) ThrowValueError(name + ": " + std::to_string(v.size()) + " values, expected 3 (x, y, z)");
  return {v[0], v[1], v[2]};
}

std::vector<double> DoublesFrom(const py::handle& value, const std::string& name) {
  const py::array_t<double, py::array::c_style | py::array::forcecast> values(RealArray(value, name));
  if (values.ndim() != 1) ThrowValueError(name + ": shape " + ShapeText(values) + ", expected a 1-D sequence");
  return {values.data(), values.data() + values.size()};
}

ChannelMajorBlock BlockFrom(const py::handle& value, const std::string& name) {
  py::array array = py::module_::import("numpy").attr("asarray")(value);
  if (array.dtype().kind() != 'f') {
    ThrowValueError(name + ": dtype " + py::str(array.dtype()).cast<std::string>() +
                    ", expected float32 or float64 samples");
  }
  if (array.ndim() != 2) {
    ThrowValueError(name + ": shape " + ShapeText(array) + ", expected (samples, channels)");
  }
  ChannelMajorBlock block;
  // forcecast + f_style: numpy makes the channel-major float32 copy only when needed.
  block.storage = py::array_t<float, py::array::f_style | py::array::forcecast>::ensure(array);
  if (!block.storage) throw py::error_already_set();
  block.samples_per_channel = static_cast<int64_t>(array.shape(0));
  block.channel_count = static_cast<int>(array.shape(1));
  return block;
}

py::array_t<float, py::array::c_style | py::array::forcecast> ChannelFrom(const py::handle& value,
                                                                          const std::string& name) {
  py::array array = py::module_::import("numpy").attr("asarray")(value);
  if (array.dtype().kind() != 'f' && array.dtype().kind() != 'i') {
    ThrowValueError(name + ": dtype " + py::str(array.dtype()).cast<std::string>() + ", expected real samples");
  }
  if (array.ndim() != 1) ThrowValueError(name + ": shape " + ShapeText(array) + ", expected 1-D samples");
  auto samples = py::array_t<float, py::array::c_style | py::array::forcecast>::ensure(array);
  if (!samples) throw py::error_already_set();
  return samples;
}

py::dtype RecordDtype(const std::vector<Column>& columns) {
  py::list descr;
  for (const Column& c : columns) {
    if (c.shape.empty()) {
      descr.append(py::make_tuple(c.name, c.format));
    } else {
      descr.append(py::make_tuple(c.name, c.format, py::tuple(py::cast(c.shape))));
    }
  }
  return py::dtype::from_args(descr);
}

RecordWriter::RecordWriter(const py::dtype& dtype, size_t rows) : dtype_(dtype) {
  array_ = py::module_::import("numpy").attr("zeros")(rows, dtype_);
  data_ = static_cast<char*>(array_.mutable_data());
  itemsize_ = static_cast<size_t>(dtype_.itemsize());
}

size_t RecordWriter::Offset(const std::string& name) const {
  return py::cast<py::tuple>(dtype_.attr("fields")[py::str(name)])[1].cast<size_t>();
}

}  // namespace localizer::python
