#include "engine/filters/filter_kind.h"

#include "engine/core/enum_names.h"

namespace localizer::engine {
namespace {

constexpr EnumName<FilterKind> kFilterKinds[] = {{FilterKind::kPf, "pf"},
                                                 {FilterKind::kEkf, "ekf"},
                                                 {FilterKind::kUkf, "ukf"},
                                                 {FilterKind::kMmpf, "mmpf"},
                                                 {FilterKind::kImm, "imm"}};

}  // namespace

StatusOr<FilterKind> ParseFilterKind(const std::string& name, const std::string& field) {
  return ParseEnumName(name, field, kFilterKinds);
}

const char* FilterKindName(FilterKind kind) { return EnumNameOf(kind, kFilterKinds); }

}  // namespace localizer::engine
