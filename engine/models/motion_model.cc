#include "engine/models/motion_model.h"

#include <cmath>

#include "engine/core/enum_names.h"
#include "engine/models/constant_acceleration.h"
#include "engine/models/constant_velocity.h"
#include "engine/models/coordinated_turn.h"
#include "engine/models/singer.h"

namespace localizer::engine {
namespace {

Status NonNegative(const char* field, double value) {
  if (value >= 0.0 && std::isfinite(value)) return Status::Ok();
  return InvalidArgument(std::string("motion model ") + field + " must be finite and >= 0, got " +
                         std::to_string(value));
}

constexpr EnumName<MotionModelKind> kMotionModelKinds[] = {{MotionModelKind::kCv, "cv"},
                                                           {MotionModelKind::kCa, "ca"},
                                                           {MotionModelKind::kCt, "ct"},
                                                           {MotionModelKind::kSinger, "singer"}};

}  // namespace

StatusOr<MotionModelKind> ParseMotionModelKind(const std::string& name, const std::string& field) {
  return ParseEnumName(name, field, kMotionModelKinds);
}

const char* MotionModelKindName(MotionModelKind kind) { return EnumNameOf(kind, kMotionModelKinds); }

StatusOr<std::unique_ptr<MotionModel>> MakeMotionModel(MotionModelKind kind, const MotionModelOptions& o) {
  switch (kind) {
    case MotionModelKind::kCv:
      LOCALIZER_RETURN_IF_ERROR(NonNegative("accel_noise_mps2", o.accel_noise_mps2));
      return std::unique_ptr<MotionModel>(std::make_unique<ConstantVelocityModel>(o.accel_noise_mps2));
    case MotionModelKind::kCa:
      LOCALIZER_RETURN_IF_ERROR(NonNegative("jerk_psd", o.jerk_psd));
      return std::unique_ptr<MotionModel>(std::make_unique<ConstantAccelerationModel>(o.jerk_psd));
    case MotionModelKind::kCt:
      LOCALIZER_RETURN_IF_ERROR(NonNegative("accel_noise_mps2", o.accel_noise_mps2));
      LOCALIZER_RETURN_IF_ERROR(NonNegative("turn_rate_noise_radps2", o.turn_rate_noise_radps2));
      return std::unique_ptr<MotionModel>(
          std::make_unique<CoordinatedTurnModel>(o.accel_noise_mps2, o.turn_rate_noise_radps2));
    case MotionModelKind::kSinger:
      if (!(o.singer_tau_s > 0.0) || !std::isfinite(o.singer_tau_s)) {
        return InvalidArgument("motion model singer_tau_s must be finite and > 0, got " +
                               std::to_string(o.singer_tau_s));
      }
      LOCALIZER_RETURN_IF_ERROR(NonNegative("singer_accel_std_mps2", o.singer_accel_std_mps2));
      return std::unique_ptr<MotionModel>(std::make_unique<SingerModel>(o.singer_tau_s, o.singer_accel_std_mps2));
  }
  return InvalidArgument("motion model kind " + std::to_string(static_cast<int>(kind)) + " is unknown");
}

}  // namespace localizer::engine
