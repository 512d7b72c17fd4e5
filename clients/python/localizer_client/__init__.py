"""Deprecated: the client's old name, kept so that scripts written for it run unchanged. New
code imports ``localizer`` (pip install --no-build-isolation ./clients/python).

What this alias keeps from the old client, where ``localizer`` changed:
  - blocks are numpy (frames, channels), frame-major as on the wire (``localizer``: (channels,
    samples), checked against the array's channel count); no client-side checks;
  - ``TrackSession.estimates()`` yields raw ``pb.Estimate`` messages and ``locate`` returns
    the ``pb.LocateResponse`` (``localizer``: ``Estimate`` / ``Fix`` dataclasses);
  - ``synth.broadband_at_sensors`` returns (samples, channels);
  - ``sources(estimate)`` reads a raw estimate's sources as dicts.
Everything else is ``localizer``'s own object.
"""
import warnings

import numpy as np

import localizer as _localizer
from localizer import (AUTHORIZATION_METADATA, SESSION_KEY_METADATA, InstanceLost,
                       add_connect_arguments, auth_metadata, bounds, close_session, connect,
                       connect_kwargs, detection_config, from_proxy_reset, imu_batch,
                       list_sessions, pb, pb_grpc, pcm16_bytes, platform_config,
                       presence_summary, read_token_file, scan, session_config,
                       tls_credentials, vector3)
from . import synth

warnings.warn("localizer_client is deprecated: import localizer (blocks are (channels, "
              "samples) there, estimates dataclasses)", DeprecationWarning, stacklevel=2)


def sample_block(sequence, data, *, encoding="float"):
    """A ``pb.SampleBlock`` from ``data`` of shape (frames, channels), frame-major as on the wire."""
    data = np.asarray(data)
    if data.ndim != 2:
        raise ValueError(f"data must have shape (frames, channels), got {data.shape}")
    if encoding == "pcm16":
        return pb.SampleBlock(sequence=sequence, channel_count=data.shape[1],
                              pcm_s16le=pcm16_bytes(data))
    if encoding != "float":
        raise ValueError(f"encoding must be 'float' or 'pcm16', got {encoding!r}")
    block = pb.SampleBlock(sequence=sequence, channel_count=data.shape[1])
    block.samples.extend(data.astype(np.float32).ravel().tolist())  # any values: the server judges
    return block


class TrackSession(_localizer.TrackSession):
    """``localizer.TrackSession`` with the old block layout and raw estimates."""

    def send(self, data, *, sequence=None, encoding="float"):
        """Queue one block (numpy (frames, channels)); returns its sequence number."""
        sequence = self.next_sequence if sequence is None else sequence
        self.send_block(sample_block(sequence, data, encoding=encoding))
        return sequence

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


def locate(channel, config, data, *, encoding="float", session_key=None, timeout=None):
    """One-shot TDOAs and fix of one block (numpy (frames, channels)): a ``pb.LocateResponse``."""
    request = pb.LocateRequest(config=config, block=sample_block(1, data, encoding=encoding))
    metadata = [(SESSION_KEY_METADATA, session_key)] if session_key else None
    return pb_grpc.LocalizerStub(channel).Locate(request, metadata=metadata, timeout=timeout)


def sources(estimate):
    """A raw direction-session estimate's sources as dicts (``localizer.Source`` is the
    dataclass): ``id``, ``status``, ``azimuth_rad``, ``elevation_rad``, ``cone_angle_rad``,
    ``direction`` (tuple), ``sigma_rad``, ``source_present``, ``power_db``, ``position_m``
    (tuple or None) and ``range_sd_m``."""
    rows = []
    for s in (_localizer.Source.from_proto(m) for m in estimate.sources):
        rows.append({"id": s.id, "status": s.status, "azimuth_rad": s.azimuth_rad,
                     "elevation_rad": s.elevation_rad, "cone_angle_rad": s.cone_angle_rad,
                     "direction": tuple(s.direction.tolist()), "sigma_rad": s.sigma_rad,
                     "source_present": s.source_present, "power_db": s.power_db,
                     "position_m": None if s.position_m is None else tuple(s.position_m.tolist()),
                     "range_sd_m": s.range_sd_m})
    return rows


__all__ = ["pb", "pb_grpc", "synth", "SESSION_KEY_METADATA", "AUTHORIZATION_METADATA", "connect",
           "tls_credentials", "read_token_file", "auth_metadata", "add_connect_arguments", "connect_kwargs",
           "vector3", "session_config", "sources", "bounds", "presence_summary", "platform_config",
           "detection_config", "sample_block", "imu_batch", "scan", "pcm16_bytes", "TrackSession", "locate",
           "list_sessions", "close_session", "InstanceLost", "from_proxy_reset"]
