"""A small client for the localizer gRPC service (proto/localizer/v1/localizer.proto).

    import localizer_client as lc
    channel = lc.connect("127.0.0.1:50051")
    config = lc.session_config(lc.synth.tetrahedron(1.5), 44100, sound_speed_mps=1500,
                               band_hz=(200, 8000), label="array-1")
    session = lc.TrackSession(channel, config)        # waits for `opened`
    session.send(block)                               # numpy (frames, channels)
    session.close()                                   # half-close: the server drains and ends OK
    for estimate in session.estimates():
        print(estimate.frame_index, estimate.position_m)

Errors: every call raises ``grpc.RpcError`` when the server ends the call with a status other
than OK; ``err.code()`` is the ``grpc.StatusCode`` (see the proto for what each means: e.g.
INVALID_ARGUMENT for a bad config, NOT_FOUND / PERMISSION_DENIED for a bad resume,
RESOURCE_EXHAUSTED when the server is full, UNAVAILABLE when it drains). A refused block does
not end the stream: it comes back as a ``rejected`` response.

Session affinity (several server instances behind a proxy, e.g. deploy/nginx/localizer.conf):
a session lives in one server instance, so every call of a session must reach the same one.
The client sends the metadata ``x-localizer-session-key`` (``SESSION_KEY_METADATA``) on every
Track stream, and on ``locate`` / ``close_session`` when given a ``session_key``; the proxy
routes by consistent hashing of it. ``TrackSession(..., session_key=...)`` sets it (default:
the config's label, else a random one) and ``reattach()`` resumes with the same key. When
resuming by hand with ``TrackSession.resume``, pass the ``session_key`` the session was opened
with: without it the session id is used, which a proxy may route to another instance (the
resume then fails with NOT_FOUND). Use any stable string, e.g. the array's name; keys that
differ spread sessions over the instances. If the instance holding a session dies, the
session is gone: its stream ends with UNAVAILABLE and resuming it fails (UNAVAILABLE or
NOT_FOUND); open a new session (the proxy sends it to a live instance). Through a proxy,
gRPC itself reports that loss as INTERNAL "Received RST_STREAM with error code 2" (the
proxy cannot send trailers for a dead upstream, it resets the stream); ``TrackSession``
raises it as ``InstanceLost`` (code UNAVAILABLE, the original error in ``.cause``), see
``from_proxy_reset``.

The generated stubs are found next to this package in the build tree, or through the
environment variable LOCALIZER_PY_GEN (see ``_stubs``); they are re-exported as ``pb`` (the
messages) and ``pb_grpc`` (the service stub).
"""
from ._stubs import pb, pb_grpc  # noqa: F401  (re-exported)
from . import synth  # noqa: F401  (re-exported)
from .connection import (SESSION_KEY_METADATA, AUTHORIZATION_METADATA, read_token_file, auth_metadata,  # noqa: F401
                         tls_credentials, connect, add_connect_arguments, connect_kwargs)
from .messages import (vector3, session_config, sources, bounds, presence_summary, platform_config,  # noqa: F401
                       detection_config, imu_batch, scan, sample_block, pcm16_bytes)
from .session import (InstanceLost, from_proxy_reset, TrackSession, locate, list_sessions,  # noqa: F401
                      close_session)

__all__ = ["pb", "pb_grpc", "synth", "SESSION_KEY_METADATA", "AUTHORIZATION_METADATA", "connect",
           "tls_credentials", "read_token_file", "auth_metadata", "add_connect_arguments", "connect_kwargs",
           "vector3", "session_config", "sources", "bounds", "presence_summary", "platform_config",
           "detection_config", "sample_block", "imu_batch", "scan", "pcm16_bytes", "TrackSession", "locate",
           "list_sessions", "close_session", "InstanceLost", "from_proxy_reset"]
