#!/usr/bin/env python3
"""Container health check: asks a localizer-server for grpc.health.v1 status.

    grpc_health_check.py [--tls-ca FILE [--tls-cert FILE --tls-key FILE] [--tls-server-name NAME]]
                         [HOST:PORT] [SERVICE]     (default 127.0.0.1:50051, "" = the server)

With --tls-ca the check speaks TLS, verifying the server against that CA, as the name
--tls-server-name (default: the host of HOST:PORT; the server certificate's SAN must hold it);
--tls-cert/--tls-key present a client certificate (a server with --tls-client-ca). The health
service needs no bearer token.

Exit 0 when the answer is SERVING, 1 when it is anything else (NOT_SERVING while the server
drains), 2 when the call fails (nothing listening, deadline). The request and response are
encoded by hand (HealthCheckRequest{service = 1}, HealthCheckResponse{status = 1}), so only
python3-grpcio is needed, not the generated health stubs.
"""
import argparse
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


def channel_for(args):
    if not args.tls_ca:
        return grpc.insecure_channel(args.target)

    def read(path):
        with open(path, "rb") as f:
            return f.read()
    credentials = grpc.ssl_channel_credentials(
        root_certificates=read(args.tls_ca),
        private_key=read(args.tls_key) if args.tls_key else None,
        certificate_chain=read(args.tls_cert) if args.tls_cert else None)
    options = [("grpc.ssl_target_name_override", args.tls_server_name)] if args.tls_server_name else []
    return grpc.secure_channel(args.target, credentials, options=options)


def main(argv):
    parser = argparse.ArgumentParser(description="grpc.health.v1 check of a localizer-server")
    parser.add_argument("target", nargs="?", default="127.0.0.1:50051")
    parser.add_argument("service", nargs="?", default="")
    parser.add_argument("--tls-ca", metavar="FILE", help="speak TLS; PEM CA certificates of the server")
    parser.add_argument("--tls-cert", metavar="FILE", help="PEM client certificate (mutual TLS)")
    parser.add_argument("--tls-key", metavar="FILE", help="PEM private key of --tls-cert")
    parser.add_argument("--tls-server-name", metavar="NAME", help="name to verify the server certificate for")
    args = parser.parse_args(argv[1:])
    target, service = args.target, args.service
    try:
        channel = channel_for(args)
    except OSError as e:
        print(f"health check of {target}: {e}", file=sys.stderr)
        return 2
    with channel:
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
