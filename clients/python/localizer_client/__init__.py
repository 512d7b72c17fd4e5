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
import collections
import queue
import uuid

import grpc
import numpy as np

from ._stubs import pb, pb_grpc  # noqa: F401  (re-exported)
from . import synth  # noqa: F401  (re-exported)

__all__ = ["pb", "pb_grpc", "synth", "SESSION_KEY_METADATA", "AUTHORIZATION_METADATA", "connect",
           "tls_credentials", "read_token_file", "auth_metadata", "add_connect_arguments", "connect_kwargs",
           "vector3",
           "session_config", "sources", "bounds", "presence_summary", "platform_config", "detection_config", "sample_block", "imu_batch",
           "scan", "pcm16_bytes", "TrackSession", "locate",
           "list_sessions", "close_session", "InstanceLost", "from_proxy_reset"]

#: Metadata key a proxy routes on, so that a resumed stream reaches the same server instance.
SESSION_KEY_METADATA = "x-localizer-session-key"


#: Metadata key of the bearer token ("authorization: Bearer TOKEN"), README "Security".
AUTHORIZATION_METADATA = "authorization"


def read_token_file(path):
    """The bearer token in ``path``: its first line that is neither blank nor a ``#`` comment;
    a ``ROLE TOKEN`` line (as in the server's --auth-token-file) also works, the last field is
    the token. ValueError naming the flag and path when there is none; OSError when unreadable."""
    with open(path, encoding="utf-8") as f:
        for line in f:
            fields = line.split()
            if fields and not fields[0].startswith("#"):
                return fields[-1]
    raise ValueError(f'--auth-token-file "{path}" holds no token')


def auth_metadata(token):
    """The metadata pair that carries ``token``, for calls made without ``connect(token=...)``."""
    return (AUTHORIZATION_METADATA, "Bearer " + token)


def tls_credentials(tls_ca=None, tls_cert=None, tls_key=None):
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

    def __init__(self, token):
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


def connect(target, *, options=(), credentials=None, tls_ca=None, tls_cert=None, tls_key=None,
            token=None, token_file=None):
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
    if token is None and token_file is not None:
        token = read_token_file(token_file)
    if token is not None:
        channel = grpc.intercept_channel(channel, _BearerToken(token))
    return channel


def add_connect_arguments(parser):
    """Adds --tls-ca, --tls-cert, --tls-key and --auth-token-file to an argparse parser (the
    same flags as localizer-cli); pass the parsed namespace to ``connect_kwargs``."""
    parser.add_argument("--tls-ca", metavar="FILE",
                        help="connect over TLS, verifying the server against these PEM CA certificates")
    parser.add_argument("--tls-cert", metavar="FILE",
                        help="PEM client certificate for mutual TLS (with --tls-key; implies TLS)")
    parser.add_argument("--tls-key", metavar="FILE", help="PEM private key of --tls-cert")
    parser.add_argument("--auth-token-file", metavar="FILE",
                        help="file holding the bearer token sent on every call (first non-'#' line)")


def connect_kwargs(args):
    """``connect`` keyword arguments from what ``add_connect_arguments`` parsed."""
    return dict(tls_ca=args.tls_ca, tls_cert=args.tls_cert, tls_key=args.tls_key,
                token_file=args.auth_token_file)


def vector3(xyz):
    """A ``pb.Vector3`` from any 3-sequence (metres or m/s)."""
    x, y, z = (float(v) for v in xyz)
    return pb.Vector3(x=x, y=y, z=z)


def session_config(sensors_m, sample_rate_hz, *, sound_speed_mps=1500.0, reference_sensor=0,
                   frame_samples=0, hop_samples=0, particles=0, band_hz=None, seed=None,
                   backend="", label="", init_region=None, platform=None, bounds=None,
                   search_radius_m=0.0, presence_false_alarm=0.0, source_timeout_s=0.0,
                   localization="", max_sources=None, source_side=None):
    """A ``pb.SessionConfig``.

    sensors_m: (C, 3) sensor positions, metres (C >= 2; a position needs 4 off a common plane).
    localization: "position", "direction" or "auto" / "" (position for a volumetric array,
    directions for a planar or linear one: SessionOpened.localization says which; each
    estimate's ``sources`` then lists the sources followed, see ``sources()``). max_sources:
    direction sessions' sources per frame, 1..16 (None: 4). source_side: (x, y, z), a planar
    array's side that holds the sources (None: not stated; mirror images). band_hz: (low, high) of
    the GCC band or None for the whole spectrum. init_region: ((xmin, ymin, zmin), (xmax, ymax,
    zmax)) or None. Zero / empty values mean "the server's default" (frame 4096, hop frame/2,
    4096 particles, seed 1, the server's --backend); SessionOpened.effective_config tells.
    platform: a ``platform_config()`` for a moving array (sensors_m then in the body frame;
    send ``imu_batch``es with ``TrackSession.send_imu`` before the blocks they cover).
    bounds: a ``bounds()`` box that can hold the source (None: unbounded). search_radius_m:
    the acquisition search radius about the array centre, m (0: 10 apertures).
    presence_false_alarm: per-frame false-alarm probability of the source-presence test, in
    (0, 0.1] (0: 0.001). source_timeout_s: how long a track coasts with no source heard
    before it is dropped, s (0: 2 s). Each estimate then says ``source_present`` (with
    ``presence_statistic`` and ``presence_threshold``), ``ambiguous`` and ``modes``.
    """
    config = pb.SessionConfig(
        array=pb.ArrayGeometry(sensors_m=[vector3(p) for p in np.asarray(sensors_m, float)],
                               sound_speed_mps=sound_speed_mps,
                               reference_sensor=reference_sensor),
        sample_rate_hz=sample_rate_hz, frame_samples=frame_samples, hop_samples=hop_samples,
        filter=pb.FilterConfig(particles=particles), backend=backend, label=label)
    if band_hz is not None:
        config.band_low_hz, config.band_high_hz = (float(f) for f in band_hz)
    if seed is not None:
        config.seed = seed
    if init_region is not None:
        config.init_region.min_m.CopyFrom(vector3(init_region[0]))
        config.init_region.max_m.CopyFrom(vector3(init_region[1]))
    if platform is not None:
        config.platform.CopyFrom(platform)
    if bounds is not None:
        config.bounds.CopyFrom(bounds)
    config.search_radius_m = float(search_radius_m)
    config.presence_false_alarm = float(presence_false_alarm)
    config.source_timeout_s = float(source_timeout_s)
    config.localization = localization
    if max_sources is not None:
        config.max_sources = int(max_sources)
    if source_side is not None:
        config.source_side.CopyFrom(vector3(source_side))
    return config


def sources(estimate):
    """A direction session's estimate as plain rows: one dict per source followed, in order of
    id, with ``id``, ``status`` ("confirmed" or "coasting"), ``azimuth_rad``,
    ``elevation_rad``, ``cone_angle_rad`` (NaN where the array cannot observe it),
    ``direction`` (a unit (x, y, z) tuple), ``sigma_rad``, ``source_present`` and ``power_db``."""
    names = {pb.TRACK_STATUS_TENTATIVE: "tentative", pb.TRACK_STATUS_CONFIRMED: "confirmed",
             pb.TRACK_STATUS_COASTING: "coasting"}
    return [{"id": s.source_id, "status": names.get(s.status, "unspecified"),
             "azimuth_rad": s.azimuth_rad, "elevation_rad": s.elevation_rad,
             "cone_angle_rad": s.cone_angle_rad,
             "direction": (s.direction.x, s.direction.y, s.direction.z),
             "sigma_rad": s.sigma_rad, "source_present": s.source_present, "power_db": s.power_db}
            for s in estimate.sources]


def bounds(min_m=None, max_m=None, *, surface_z_m=None, bottom_z_m=None):
    """A ``pb.Bounds``: the box that can hold the source, metres, world frame.

    min_m, max_m: (x, y, z) corners or None; an axis that is None or infinite (-inf in min_m,
    +inf in max_m) is open (left unset on the wire). A water column with z up:
    ``bounds(surface_z_m=0.0, bottom_z_m=-8.0)`` (the surface is the upper z side, the
    bottom the lower; giving one together with that side of max_m / min_m is a ValueError).
    The server refuses a side that is not finite or an axis whose min is not below its max
    with INVALID_ARGUMENT naming the field (``bounds.min_z_m``, ...).
    """
    b = pb.Bounds()
    for corner, prefix in ((min_m, "min"), (max_m, "max")):
        if corner is None:
            continue
        for axis, value in zip("xyz", corner):
            if value is None:
                continue
            value = float(value)
            if np.isinf(value) and (value < 0) == (prefix == "min"):
                continue  # open side
            setattr(b, f"{prefix}_{axis}_m", value)
    for value, field in ((surface_z_m, "max_z_m"), (bottom_z_m, "min_z_m")):
        if value is None:
            continue
        if b.HasField(field):
            raise ValueError(f"bounds: {field} given twice (as a corner and as the "
                             f"{'surface' if field == 'max_z_m' else 'bottom'})")
        setattr(b, field, float(value))
    return b


def presence_summary(estimates):
    """Source presence over a run: a dict with ``frames``, ``tested`` (estimates whose
    presence test ran: threshold > 0), ``present``, ``ambiguous``, ``max_statistic`` and the
    ``threshold`` of that frame, and ``no_source`` (frames were tested and none held a
    source; the line ``localizer-cli`` prints then is ``no_source_line``); ``initialised``
    (positions) and ``far_field`` (of those, the ones whose frame could not bound the range:
    trust their direction from the array's centroid, not their range)."""
    out = {"frames": 0, "tested": 0, "present": 0, "ambiguous": 0, "max_statistic": 0.0,
           "threshold": 0.0, "initialised": 0, "far_field": 0}
    for e in estimates:
        out["frames"] += 1
        out["present"] += int(e.source_present)
        out["ambiguous"] += int(e.ambiguous)
        out["initialised"] += int(e.initialised)
        out["far_field"] += int(e.initialised and e.far_field)
        if e.presence_threshold > 0.0:
            if out["tested"] == 0 or e.presence_statistic > out["max_statistic"]:
                out["max_statistic"] = e.presence_statistic
                out["threshold"] = e.presence_threshold
            out["tested"] += 1
    out["no_source"] = out["tested"] > 0 and out["present"] == 0
    out["no_source_line"] = (
        f"no source found in {out['frames']} frames (presence statistic max "
        f"{out['max_statistic']:.3g}, threshold {out['threshold']:.3g})" if out["no_source"] else "")
    return out


def platform_config(*, attitude_filter="", use_magnetometer=False, mag_declination_rad=0.0,
                    origin_m=(0.0, 0.0, 0.0)):
    """A ``pb.PlatformConfig``: the array rides a platform whose attitude comes from its IMU
    ("quaternion" filter by default, or "euler"); origin_m: the body origin in the world."""
    return pb.PlatformConfig(attitude_filter=attitude_filter, use_magnetometer=use_magnetometer,
                             mag_declination_rad=mag_declination_rad, origin_m=vector3(origin_m))


def detection_config(*, label="", dimensions=0, range_sigma_m=0.0, bearing_sigma_rad=0.0,
                     **detections):
    """A ``pb.SessionConfig`` for a detection (track-while-scan) session: the session takes
    ``scan()``s of plots and answers each with a ``pb.TrackList``. Keyword arguments are
    ``pb.DetectionConfig`` fields (confirm_hits, gate_probability, ...); 0 means the default."""
    d = pb.DetectionConfig(dimensions=dimensions, range_sigma_m=range_sigma_m,
                           bearing_sigma_rad=bearing_sigma_rad, **detections)
    return pb.SessionConfig(detections=d, label=label)


def imu_batch(sequence, t_s, gyro_rps, accel_mps2, mag_uT=None, origin_m=None):
    """A ``pb.ImuBatch`` from arrays: t_s (N,), gyro_rps and accel_mps2 (N, 3), mag_uT (N, 3)
    or None; times on the session clock (seconds from its first audio sample), increasing."""
    batch = pb.ImuBatch(sequence=sequence)
    t_s = np.asarray(t_s, float)
    gyro, accel = np.asarray(gyro_rps, float), np.asarray(accel_mps2, float)
    mag = None if mag_uT is None else np.asarray(mag_uT, float)
    for i in range(len(t_s)):
        sample = batch.samples.add(t_s=float(t_s[i]), gyro_rps=vector3(gyro[i]),
                                   accel_mps2=vector3(accel[i]))
        if mag is not None:
            sample.mag_uT.CopyFrom(vector3(mag[i]))
    if origin_m is not None:
        batch.origin_m.CopyFrom(vector3(origin_m))
    return batch


def scan(sequence, time_s, ranges_m, bearings_rad, *, elevations_rad=None, snr_db=None,
         sensor_position_m=(0.0, 0.0, 0.0)):
    """A ``pb.Scan``: one sensor revolution's plots (range m, bearing rad from +x towards +y,
    optional elevation rad and SNR dB) at time_s, the sensor at sensor_position_m."""
    s = pb.Scan(sequence=sequence, time_s=float(time_s), sensor_position_m=vector3(sensor_position_m))
    for i, (r, b) in enumerate(zip(ranges_m, bearings_rad)):
        d = s.detections.add(range_m=float(r), bearing_rad=float(b))
        if elevations_rad is not None:
            d.elevation_rad = float(elevations_rad[i])
        if snr_db is not None:
            d.snr_db = float(snr_db[i])
    return s


def sample_block(sequence, data, *, encoding="float"):
    """A ``pb.SampleBlock`` from ``data`` of shape (frames, channels), frame-major as on the wire.

    encoding "float": ``samples`` as float32; "pcm16": ``pcm_s16le`` (value * 32768, clipped).
    """
    data = np.asarray(data)
    if data.ndim != 2:
        raise ValueError(f"data must have shape (frames, channels), got {data.shape}")
    block = pb.SampleBlock(sequence=sequence, channel_count=data.shape[1])
    if encoding == "float":
        block.samples.extend(data.astype(np.float32).ravel().tolist())
    elif encoding == "pcm16":
        block.pcm_s16le = pcm16_bytes(data)
    else:
        raise ValueError(f"encoding must be 'float' or 'pcm16', got {encoding!r}")
    return block


def pcm16_bytes(data):
    """16-bit little-endian PCM of ``data`` (any shape, amplitude 1 = full scale), C order."""
    scaled = np.clip(np.round(np.asarray(data, np.float64) * 32768.0), -32768, 32767)
    return scaled.astype("<i2").tobytes()


class InstanceLost(grpc.RpcError):
    """The server instance behind a proxy died under a call: code() is UNAVAILABLE, as a
    direct connection reports it; ``cause`` is the proxy's reset as gRPC reported it."""

    def __init__(self, cause):
        super().__init__(cause)
        self.cause = cause

    def code(self):
        return grpc.StatusCode.UNAVAILABLE

    def details(self):
        return ("the server instance behind the proxy is gone (the proxy reset the stream: "
                f"{self.cause.details()})")

    def initial_metadata(self):
        return self.cause.initial_metadata()

    def trailing_metadata(self):
        return self.cause.trailing_metadata()

    def __str__(self):
        return f"UNAVAILABLE: {self.details()}"


def _is_proxy_reset(code, details):
    # Our server always ends a call with a status; an HTTP/2 reset with INTERNAL_ERROR (2)
    # comes from a proxy whose upstream connection broke.
    return code == grpc.StatusCode.INTERNAL and "RST_STREAM with error code 2" in (details or "")


def from_proxy_reset(err):
    """``err`` (a grpc.RpcError) as ``InstanceLost`` when it is a proxy's reset of a stream
    whose instance died, else ``err`` itself."""
    try:
        code, details = err.code(), err.details()
    except Exception:  # an RpcError without a status (e.g. raised before the call started)
        return err
    return InstanceLost(err) if _is_proxy_reset(code, details) else err


class TrackSession:
    """One Track stream: open (``config``) or resume (``resume``) a session, send blocks, read
    responses. The constructor waits for the ``opened`` response and raises ``grpc.RpcError``
    if the stream ends instead (INVALID_ARGUMENT, NOT_FOUND, PERMISSION_DENIED, ...).

    Attributes: ``opened`` (pb.SessionOpened), ``session_id``, ``resume_token``,
    ``session_key`` (sent as metadata x-localizer-session-key on this and every resumed
    stream), ``last_frame_received`` (frame_index of the last estimate read, or None),
    ``next_sequence`` (what ``send`` uses next), ``rejected`` and ``gaps`` (the BlockRejected
    and SequenceGap responses seen by ``estimates()``).

    Reading and sending may happen on different threads. After a broken stream, ``reattach()``
    resumes the session on a new stream, asking for the estimates after
    ``last_frame_received``.
    """

    def __init__(self, channel, config=None, *, resume=None, session_key=None, timeout=None):
        if (config is None) == (resume is None):
            raise ValueError("give exactly one of config (open) and resume")
        self._channel = channel
        self.session_key = session_key or (resume.session_id if resume is not None
                                           else config.label or uuid.uuid4().hex)
        self.last_frame_received = None
        if resume is not None and resume.HasField("last_frame_received"):
            self.last_frame_received = resume.last_frame_received
        self.rejected, self.gaps = [], []
        self._requests = queue.SimpleQueue()
        self._requests.put(pb.TrackRequest(open=config) if config is not None
                           else pb.TrackRequest(resume=resume))
        self._call = pb_grpc.LocalizerStub(channel).Track(
            self._request_iterator(), metadata=[(SESSION_KEY_METADATA, self.session_key)],
            timeout=timeout)
        try:
            first = next(self._call, None)  # raises grpc.RpcError if the stream ends with an error
        except grpc.RpcError as err:
            mapped = from_proxy_reset(err)
            if mapped is err:
                raise
            raise mapped from err
        if first is None or first.WhichOneof("kind") != "opened":
            self.cancel()
            raise RuntimeError(f"Track: expected `opened` first, got {first!r}")
        self.opened = first.opened
        self.session_id = self.opened.session_id
        self.resume_token = self.opened.resume_token
        self.next_sequence = (self.opened.last_sequence + 1
                              if self.opened.HasField("last_sequence") else 1)

    @classmethod
    def resume(cls, channel, session_id, resume_token, *, last_frame_received=None,
               session_key=None, timeout=None):
        """Resume a detached session (use the session_key it was opened with, if any).

        ``last_frame_received``: frame_index of the last estimate this client holds; None when
        it holds none (sent as ``received_none``: every estimate the server still has is
        sent again, frame 0 first)."""
        req = pb.ResumeSession(session_id=session_id, resume_token=resume_token)
        if last_frame_received is not None:
            req.last_frame_received = last_frame_received
        else:
            # This client holds no estimate: ask for all the server still has, frame 0
            # included (last_frame_received=0 would mean "frame 0 received").
            req.received_none = True
        return cls(channel, resume=req, session_key=session_key, timeout=timeout)

    def reattach(self, channel=None, *, timeout=None):
        """A new TrackSession resuming this one (same session key), e.g. after its stream broke."""
        return TrackSession.resume(channel or self._channel, self.session_id, self.resume_token,
                                   last_frame_received=self.last_frame_received,
                                   session_key=self.session_key, timeout=timeout)

    def _request_iterator(self):
        while True:
            request = self._requests.get()
            if request is None:
                return
            yield request

    def send(self, data, *, sequence=None, encoding="float"):
        """Queue one block (numpy (frames, channels)); returns its sequence number.

        ``sequence`` defaults to ``next_sequence``; either way ``next_sequence`` becomes
        sequence + 1. Problems with the block come back as a ``rejected`` response.
        """
        sequence = self.next_sequence if sequence is None else sequence
        self.send_block(sample_block(sequence, data, encoding=encoding))
        return sequence

    def send_block(self, block):
        """Queue a ready ``pb.SampleBlock`` as is."""
        self.next_sequence = block.sequence + 1
        self._requests.put(pb.TrackRequest(block=block))

    def send_imu(self, batch):
        """Queue a ``pb.ImuBatch`` (moving-array sessions; ``imu_batch()``). A bad batch comes
        back as a ``rejected`` response with request "imu"."""
        self._requests.put(pb.TrackRequest(imu=batch))

    def send_scan(self, scan_message):
        """Queue a ``pb.Scan`` (detection sessions; ``scan()``); its answer is a ``tracks``
        response (``track_lists()``), a bad one a ``rejected`` response with request "scan"."""
        self._requests.put(pb.TrackRequest(scan=scan_message))

    def track_lists(self):
        """Detection sessions: the ``pb.TrackList`` responses only; rejections go to
        .rejected."""
        for response in self:
            kind = response.WhichOneof("kind")
            if kind == "tracks":
                yield response.tracks
            elif kind == "rejected":
                self.rejected.append(response.rejected)

    def close(self):
        """Half-close: no more blocks. The server processes what it accepted, sends the
        remaining estimates, ends the stream OK and closes the session."""
        self._requests.put(None)

    def cancel(self):
        """Break the stream; the session stays on the server, detached and resumable."""
        self._call.cancel()
        self._requests.put(None)

    def __iter__(self):
        """Every TrackResponse after `opened`, in order; raises grpc.RpcError on an error end
        (``InstanceLost`` when a proxy reset the stream because its instance died)."""
        try:
            for response in self._call:
                if response.WhichOneof("kind") == "estimate":
                    self.last_frame_received = response.estimate.frame_index
                yield response
        except grpc.RpcError as err:
            mapped = from_proxy_reset(err)
            if mapped is err:
                raise
            raise mapped from err
        finally:
            self._requests.put(None)  # the stream is over: release the request thread

    def estimates(self):
        """The ``pb.Estimate`` responses only; rejections and gaps go to .rejected / .gaps."""
        for response in self:
            kind = response.WhichOneof("kind")
            if kind == "estimate":
                yield response.estimate
            elif kind == "rejected":
                self.rejected.append(response.rejected)
            elif kind == "gap":
                self.gaps.append(response.gap)

    def code(self):
        """The stream's final grpc.StatusCode (blocks until it ends); UNAVAILABLE for a
        proxy's reset after its instance died."""
        code = self._call.code()
        return grpc.StatusCode.UNAVAILABLE if _is_proxy_reset(code, self._call.details()) else code

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.cancel() if exc[0] is not None else self.close()
        return False


def locate(channel, config, data, *, encoding="float", session_key=None, timeout=None):
    """One-shot TDOAs and multilateration fix of one block (numpy (frames, channels)):
    a ``pb.LocateResponse``. No session is created."""
    request = pb.LocateRequest(config=config, block=sample_block(1, data, encoding=encoding))
    metadata = [(SESSION_KEY_METADATA, session_key)] if session_key else None
    return pb_grpc.LocalizerStub(channel).Locate(request, metadata=metadata, timeout=timeout)


def list_sessions(channel, *, timeout=None):
    """The sessions the server holds (attached or detached): a list of ``pb.SessionInfo``."""
    response = pb_grpc.LocalizerStub(channel).ListSessions(pb.ListSessionsRequest(),
                                                            timeout=timeout)
    return list(response.sessions)


def close_session(channel, session_id, resume_token, *, session_key=None, timeout=None):
    """End a session now (its stream, if any, ends CANCELLED): a ``pb.CloseSessionResponse``.
    PERMISSION_DENIED with the wrong token, NOT_FOUND if unknown."""
    metadata = [(SESSION_KEY_METADATA, session_key)] if session_key else None
    return pb_grpc.LocalizerStub(channel).CloseSession(
        pb.CloseSessionRequest(session_id=session_id, resume_token=resume_token),
        metadata=metadata, timeout=timeout)
