"""Connecting to a localizer server: TLS and mutual TLS credentials, bearer tokens (a call
interceptor), the session-affinity metadata, and the matching command-line arguments.
``localizer.aio.connect`` makes the asyncio channel from the same pieces."""
from __future__ import annotations

import argparse
import collections

import grpc

#: Metadata key a proxy routes on, so that a resumed stream reaches the same server instance.
SESSION_KEY_METADATA = "x-localizer-session-key"


#: Metadata key of the bearer token ("authorization: Bearer TOKEN"), docs/SECURITY.md.
AUTHORIZATION_METADATA = "authorization"


def read_token_file(path: str) -> str:
    """The bearer token in ``path``: its first line that is neither blank nor a ``#`` comment;
    a ``ROLE TOKEN`` line (as in the server's --auth-token-file) also works, the last field is
    the token. ValueError naming the flag and path when there is none; OSError when unreadable."""
    with open(path, encoding="utf-8") as f:
        for line in f:
            fields = line.split()
            if fields and not fields[0].startswith("#"):
                return fields[-1]
    raise ValueError(f'--auth-token-file "{path}" holds no token')


def auth_metadata(token: str) -> tuple[str, str]:
    """The metadata pair that carries ``token``, for calls made without ``connect(token=...)``."""
    return (AUTHORIZATION_METADATA, "Bearer " + token)


def tls_credentials(tls_ca: str | None = None, tls_cert: str | None = None,
                    tls_key: str | None = None) -> grpc.ChannelCredentials | None:
    """``grpc.ssl_channel_credentials`` from PEM files (None when all three are None): the
    server is verified against ``tls_ca`` (None: the system's roots); ``tls_cert`` and
    ``tls_key`` (together) are the client certificate for mutual TLS."""
    if tls_ca is None and tls_cert is None and tls_key is None:
        return None
    if (tls_cert is None) != (tls_key is None):
        raise ValueError("--tls-cert and --tls-key go together (both or neither)")

    def read(path):
        with open(path, "rb") as f:
            return f.read()
    return grpc.ssl_channel_credentials(
        root_certificates=read(tls_ca) if tls_ca else None,
        private_key=read(tls_key) if tls_key else None,
        certificate_chain=read(tls_cert) if tls_cert else None)


class _CallDetails(collections.namedtuple(
        "_CallDetails", ("method", "timeout", "metadata", "credentials", "wait_for_ready", "compression")),
        grpc.ClientCallDetails):
    pass


class _BearerToken(grpc.UnaryUnaryClientInterceptor, grpc.UnaryStreamClientInterceptor,
                   grpc.StreamUnaryClientInterceptor, grpc.StreamStreamClientInterceptor):
    """Adds ``authorization: Bearer TOKEN`` to every call (over TLS or plaintext)."""

    def __init__(self, token: str):
        self._pair = auth_metadata(token)

    def _details(self, d):
        metadata = list(d.metadata or []) + [self._pair]
        return _CallDetails(d.method, d.timeout, metadata, d.credentials,
                            getattr(d, "wait_for_ready", None), getattr(d, "compression", None))

    def intercept_unary_unary(self, continuation, details, request):
        return continuation(self._details(details), request)

    def intercept_unary_stream(self, continuation, details, request):
        return continuation(self._details(details), request)

    def intercept_stream_unary(self, continuation, details, request_iterator):
        return continuation(self._details(details), request_iterator)

    def intercept_stream_stream(self, continuation, details, request_iterator):
        return continuation(self._details(details), request_iterator)


def resolve_token(token: str | None, token_file: str | None) -> str | None:
    """``token``, else the token in ``token_file`` (None when both are None)."""
    if token is None and token_file is not None:
        return read_token_file(token_file)
    return token


def connect(target: str, *, options=(), credentials: grpc.ChannelCredentials | None = None,
            tls_ca: str | None = None, tls_cert: str | None = None, tls_key: str | None = None,
            token: str | None = None, token_file: str | None = None) -> grpc.Channel:
    """A channel to ``target`` ("host:port").

    TLS when ``credentials`` (grpc.ChannelCredentials) or any of ``tls_ca`` / ``tls_cert`` /
    ``tls_key`` (PEM file paths, see ``tls_credentials``) is given, else plaintext. ``token``
    (or the token in ``token_file``, see ``read_token_file``) is sent as ``authorization:
    Bearer TOKEN`` on every call."""
    if credentials is None:
        credentials = tls_credentials(tls_ca, tls_cert, tls_key)
    if credentials is not None:
        channel = grpc.secure_channel(target, credentials, options=list(options))
    else:
        channel = grpc.insecure_channel(target, options=list(options))
    token = resolve_token(token, token_file)
    if token is not None:
        channel = grpc.intercept_channel(channel, _BearerToken(token))
    return channel


def add_connect_arguments(parser: argparse.ArgumentParser) -> None:
    """Adds --tls-ca, --tls-cert, --tls-key and --auth-token-file to an argparse parser (the
    same flags as localizer-cli); pass the parsed namespace to ``connect_kwargs``."""
    parser.add_argument("--tls-ca", metavar="FILE",
                        help="connect over TLS, verifying the server against these PEM CA certificates")
    parser.add_argument("--tls-cert", metavar="FILE",
                        help="PEM client certificate for mutual TLS (with --tls-key; implies TLS)")
    parser.add_argument("--tls-key", metavar="FILE", help="PEM private key of --tls-cert")
    parser.add_argument("--auth-token-file", metavar="FILE",
                        help="file holding the bearer token sent on every call (first non-'#' line)")


def connect_kwargs(args: argparse.Namespace) -> dict:
    """``connect`` keyword arguments from what ``add_connect_arguments`` parsed."""
    return dict(tls_ca=args.tls_ca, tls_cert=args.tls_cert, tls_key=args.tls_key,
                token_file=args.auth_token_file)
