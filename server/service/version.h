// The version this build reports (localizer_build_info, --version, SessionOpened logs).
#pragma once

namespace localizer::server {
inline constexpr const char* kLocalizerVersion = "0.3.0";
}  // namespace localizer::server
