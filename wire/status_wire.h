// The one place where engine Status codes become gRPC status codes (and back to names).
// Each StatusCode maps to the gRPC code of the same name.
#pragma once

#include <grpcpp/support/status.h>

#include "engine/core/status.h"

namespace localizer::wire {

grpc::Status ToGrpcStatus(const Status& status);
// "INVALID_ARGUMENT", "UNAVAILABLE", ... as gRPC spells them.
const char* GrpcCodeName(grpc::StatusCode code);

// The reverse, for clients: a gRPC status as a localizer Status whose message starts with
// the gRPC code name, "INVALID_ARGUMENT: array.sensors_m has 3 sensors ...", so nothing is
// lost where the code has no StatusCode of its own. Codes without one map to the nearest:
// DEADLINE_EXCEEDED and ABORTED -> kUnavailable (worth a retry), UNAUTHENTICATED ->
// kPermissionDenied, ALREADY_EXISTS and UNIMPLEMENTED -> kFailedPrecondition, UNKNOWN and
// DATA_LOSS -> kInternal. An OK status stays OK (and keeps no message).
Status FromGrpcStatus(const grpc::Status& status);

}  // namespace localizer::wire
