#!/usr/bin/env python3
"""Container health check: asks a localizer-server for grpc.health.v1 status.

    grpc_health_check.py [HOST:PORT] [SERVICE]     (default 127.0.0.1:50051, "" = the server)

Exit 0 when the answer is SERVING, 1 when it is anything else (NOT_SERVING while the server
drains), 2 when the call fails (nothing listening, deadline). The request and response are
encoded by hand (HealthCheckRequest{service = 1}, HealthCheckResponse{status = 1}), so only
python3-grpcio is needed, not the generated health stubs.
"""
import sys

import grpc

SERVING = 1


def encode_request(service):
    data = service.encode()
    if not data:
        return b""
    if len(data) > 127:
        raise ValueError("service name longer than 127 bytes")
    return b"\x0a" + bytes([len(data)]) + data


def decode_status(response):
    """HealthCheckResponse.status (field 1, varint); absent means UNKNOWN (0)."""
    if len(response) >= 2 and response[0] == 0x08:
        return response[1]
    return 0


def main(argv):
    target = argv[1] if len(argv) > 1 else "127.0.0.1:50051"
    service = argv[2] if len(argv) > 2 else ""
    with grpc.insecure_channel(target) as channel:
        check = channel.unary_unary("/grpc.health.v1.Health/Check")
        try:
            status = decode_status(check(encode_request(service), timeout=3.0))
        except grpc.RpcError as e:
            print(f"health check of {target}: {e.code().name}: {e.details()}", file=sys.stderr)
            return 2
    print(f"health check of {target}: status {status} ({'SERVING' if status == SERVING else 'not serving'})")
    return 0 if status == SERVING else 1


if __name__ == "__main__":
    sys.exit(main(sys.argv))
