#include "clients/io/json_fields.h"

#include <cmath>

namespace localizer::io {

using nlohmann::json;

StatusOr<double> FiniteNumber(const json& value, const std::string& source, const std::string& field) {
  if (!value.is_number()) {
    return InvalidArgument(source + ": " + field + " is " + value.dump() + ", not a number");
  }
  const double x = value.get<double>();
  if (!std::isfinite(x)) return InvalidArgument(source + ": " + field + " is not finite");
  return x;
}

StatusOr<engine::Vec3> FiniteVector(const json& value, const std::string& source, const std::string& field) {
  if (!value.is_array() || value.size() != 3) {
    return InvalidArgument(source + ": " + field + " must be [x, y, z], got " + value.dump());
  }
  engine::Vec3 out;
  for (int axis = 0; axis < 3; ++axis) {
    auto x = FiniteNumber(value[static_cast<size_t>(axis)], source, field);
    if (!x.ok()) return x.status();
    out[axis] = *x;
  }
  return out;
}

StatusOr<double> PositiveNumber(const json& value, const std::string& source, const std::string& field) {
  auto x = FiniteNumber(value, source, field);
  if (x.ok() && *x <= 0.0) {
    return InvalidArgument(source + ": " + field + " is " + value.dump() + ", must be > 0");
  }
  return x;
}

}  // namespace localizer::io
