"""Python client of the localizer service (proto/localizer/v1/localizer.proto).

    import numpy as np, localizer
    channel = localizer.connect("127.0.0.1:50051")
    config = localizer.session_config(sensors_m, 44100.0, sound_speed_mps=1500.0,
                                      band_hz=(200, 8000), seed=1, label="array-1")
    session = localizer.TrackSession.open(channel, config)   # waits for `opened`
    session.send(block)            # numpy (channels, samples), float32 or float64
    session.close()                # half-close: the server drains and ends OK
    for e in session.estimates():  # localizer.Estimate dataclasses, SI units
        print(e.frame_index, e.t_s, e.position_m, e.covariance, e.source_present)

Blocks are (channels, samples) arrays, channel k = sensor k (``localizer.audio.read`` gives
a recording that way); a wrong shape, dtype or a non-finite sample is a ValueError before
anything is sent. Estimates are ``Estimate`` dataclasses with the message in ``.raw``;
``localizer.aio`` is the same client for asyncio. ``pb`` / ``pb_grpc`` are the generated
messages and service stub (``localizer.v1.localizer_pb2`` / ``_pb2_grpc``).

Errors: every call raises ``grpc.RpcError`` when the server ends the call with a status other
than OK; ``err.code()`` is the ``grpc.StatusCode`` (see the proto for what each means: e.g.
INVALID_ARGUMENT for a bad config, NOT_FOUND / PERMISSION_DENIED for a bad resume,
RESOURCE_EXHAUSTED when the server is full, UNAVAILABLE when it drains). A block the server
refuses does not end the stream: it comes back as a ``rejected`` response (``.rejected``).

Session affinity (several server instances behind a proxy, e.g. deploy/nginx/localizer.conf):
a session lives in one server instance, so every call of a session must reach the same one.
The client sends the metadata ``x-localizer-session-key`` (``SESSION_KEY_METADATA``) on every
Track stream, and on ``locate`` / ``close_session`` when given a ``session_key``; the proxy
routes by consistent hashing of it. ``TrackSession(..., session_key=...)`` sets it (default:
the config's label, else a random one) and ``reattach()`` resumes with the same key. When
resuming by hand with ``TrackSession.resume``, pass the ``session_key`` the session was opened
with: without it the session id is used, which a proxy may route to another instance (the
resume then fails with NOT_FOUND). If the instance holding a session dies, the session is
gone: its stream ends with UNAVAILABLE and resuming it fails (UNAVAILABLE or NOT_FOUND); open
a new session. Through a proxy, gRPC itself reports that loss as INTERNAL "Received
RST_STREAM with error code 2" (the proxy cannot send trailers for a dead upstream); the
client raises it as ``InstanceLost`` (code UNAVAILABLE, the original error in ``.cause``),
see ``from_proxy_reset``.

A session file (an ``array.json`` with its optional ``"session"`` object of settings, read the
same by ``localizer-cli``): ``read_session_file(path)`` gives a ``SessionFile`` whose
``to_session_config(sample_rate_hz)`` is the ``pb.SessionConfig`` to open and whose
``engine_options(sample_rate_hz)`` are ``localizer.engine.Session``'s keyword options.

``__version__`` is the project version (CMake's project(VERSION)), written into
``_version.py`` by the build that made this copy (setup.py or the CMake target).
"""
from ._stubs import pb, pb_grpc
from . import audio, synth  # audio imports soundfile only when it reads
from ._track import InstanceLost, from_proxy_reset
from .blocks import check_samples, pcm16_bytes, sample_block
from .connection import (AUTHORIZATION_METADATA, SESSION_KEY_METADATA, add_connect_arguments,
                         auth_metadata, connect, connect_kwargs, read_token_file, tls_credentials)
from .estimates import Estimate, Fix, PairTdoa, PlatformPose, Source, StageLatency
from .messages import (bounds, detection_config, imu_batch, platform_config, presence_summary,
                       scan, session_config, vector3)
from .session import TrackSession, close_session, list_sessions, locate
from .session_file import SessionFile, parse_session_file, read_session_file

try:
    from ._version import __version__
except ImportError:  # the source tree, used in place: no build wrote _version.py
    __version__ = "0+unknown"

__all__ = ["__version__", "pb", "pb_grpc", "audio", "synth",
           "SESSION_KEY_METADATA", "AUTHORIZATION_METADATA", "connect", "tls_credentials",
           "read_token_file", "auth_metadata", "add_connect_arguments", "connect_kwargs",
           "vector3", "session_config", "bounds", "presence_summary", "platform_config",
           "detection_config", "imu_batch", "scan",
           "check_samples", "sample_block", "pcm16_bytes",
           "Estimate", "Fix", "PairTdoa", "PlatformPose", "Source", "StageLatency",
           "TrackSession", "locate", "list_sessions", "close_session", "InstanceLost",
           "from_proxy_reset", "SessionFile", "read_session_file", "parse_session_file"]
