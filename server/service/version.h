// The version this build reports (localizer_build_info, --version, SessionOpened logs):
// engine/core/version.h's, shared with the CLI.
#pragma once

#include "engine/core/version.h"

namespace localizer::server {
using localizer::kLocalizerVersion;
}  // namespace localizer::server
