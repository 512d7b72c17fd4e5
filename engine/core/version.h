// The version every program of this build reports (localizer-cli --version, localizer-server
// --version, localizer_build_info, the live view). Kept equal to CMake's project(VERSION).
#pragma once

namespace localizer {
inline constexpr const char* kLocalizerVersion = "0.3.0";
}  // namespace localizer
