// Typed fields of a JSON document (array.json, room scenes), each error naming the source
// (usually the file's path) and the field.
#pragma once

#include <nlohmann/json.hpp>
#include <string>

#include "engine/core/status.h"
#include "engine/core/types.h"

namespace localizer::io {

// A finite number at `value`, or INVALID_ARGUMENT naming `field`.
StatusOr<double> FiniteNumber(const nlohmann::json& value, const std::string& source, const std::string& field);
// The same, and > 0.
StatusOr<double> PositiveNumber(const nlohmann::json& value, const std::string& source, const std::string& field);
// Three finite numbers [x, y, z].
StatusOr<engine::Vec3> FiniteVector(const nlohmann::json& value, const std::string& source, const std::string& field);

}  // namespace localizer::io
