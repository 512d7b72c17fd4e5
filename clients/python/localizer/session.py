"""Calls on a connected (synchronous) channel: a Track stream (``TrackSession``, resumable,
with proxy-loss detection), one-shot ``locate``, and the operator calls ``list_sessions`` /
``close_session``. ``localizer.aio`` has the same calls for asyncio."""
from __future__ import annotations

import queue
from typing import Iterator

import grpc
import numpy.typing as npt

from ._stubs import pb, pb_grpc
from ._track import StreamState, from_proxy_reset, is_proxy_reset, resume_request
from .blocks import sample_block
from .connection import SESSION_KEY_METADATA
from .estimates import Estimate, Fix

__all__ = ["TrackSession", "locate", "list_sessions", "close_session"]


class TrackSession(StreamState):
    """One Track stream: open (``config``) or resume (``resume``) a session, send blocks, read
    estimates. The constructor (or ``TrackSession.open``) waits for the ``opened`` response
    and raises ``grpc.RpcError`` if the stream ends instead (INVALID_ARGUMENT, NOT_FOUND,
    PERMISSION_DENIED, ...). Attributes: see ``StreamState``.

    Reading and sending may happen on different threads (sending only queues). After a broken
    stream, ``reattach()`` resumes the session on a new stream, asking for the estimates after
    ``last_frame_received``.
    """

    def __init__(self, channel: grpc.Channel, config: pb.SessionConfig | None = None, *,
                 resume: pb.ResumeSession | None = None, session_key: str | None = None,
                 timeout: float | None = None):
        first_request = self._start(config, resume, session_key)
        self._channel = channel
        self._requests: queue.SimpleQueue = queue.SimpleQueue()
        self._requests.put(first_request)
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
        if not self._opened(first):
            self.cancel()
            raise RuntimeError(f"Track: expected `opened` first, got {first!r}")

    @classmethod
    def open(cls, channel: grpc.Channel, config: pb.SessionConfig, *,
             session_key: str | None = None, timeout: float | None = None) -> TrackSession:
        """Open a session (the constructor; named as ``await aio.TrackSession.open(...)``)."""
        return cls(channel, config, session_key=session_key, timeout=timeout)

    @classmethod
    def resume(cls, channel: grpc.Channel, session_id: str, resume_token: str, *,
               last_frame_received: int | None = None, session_key: str | None = None,
               timeout: float | None = None) -> TrackSession:
        """Resume a detached session (use the session_key it was opened with, if any).

        ``last_frame_received``: frame_index of the last estimate this client holds; None when
        it holds none (every estimate the server still has is sent again, frame 0 first)."""
        return cls(channel, resume=resume_request(session_id, resume_token, last_frame_received),
                   session_key=session_key, timeout=timeout)

    def reattach(self, channel: grpc.Channel | None = None, *,
                 timeout: float | None = None) -> TrackSession:
        """A new session object resuming this one (same session key), e.g. after its stream broke."""
        return type(self).resume(channel or self._channel, self.session_id, self.resume_token,
                                 last_frame_received=self.last_frame_received,
                                 session_key=self.session_key, timeout=timeout)

    def _request_iterator(self):
        while True:
            request = self._requests.get()
            if request is None:
                return
            yield request

    def send(self, samples: npt.ArrayLike, *, sequence: int | None = None,
             encoding: str = "float") -> int:
        """Queue one block, shape (channels, samples), float32 or float64; returns its sequence
        number. A block of the wrong shape, dtype or with a non-finite sample is a ValueError
        here; what the server refuses comes back as a ``rejected`` response.

        ``sequence`` defaults to ``next_sequence``; either way ``next_sequence`` becomes
        sequence + 1. encoding "pcm16" sends 16-bit PCM (half the bytes, clipped at +-1)."""
        request = self._block_request(samples, sequence, encoding)
        self._requests.put(request)
        return request.block.sequence

    def send_block(self, block: pb.SampleBlock) -> None:
        """Queue a ready ``pb.SampleBlock`` as is (no client-side checks)."""
        self._requests.put(self._raw_block_request(block))

    def send_imu(self, batch: pb.ImuBatch) -> None:
        """Queue a ``pb.ImuBatch`` (moving-array sessions; ``imu_batch()``). A bad batch comes
        back as a ``rejected`` response with request "imu"."""
        self._requests.put(pb.TrackRequest(imu=batch))

    def send_scan(self, scan_message: pb.Scan) -> None:
        """Queue a ``pb.Scan`` (detection sessions; ``scan()``); its answer is a ``tracks``
        response (``track_lists()``), a bad one a ``rejected`` response with request "scan"."""
        self._requests.put(pb.TrackRequest(scan=scan_message))

    def close(self) -> None:
        """Half-close: no more blocks. The server processes what it accepted, sends the
        remaining estimates, ends the stream OK and closes the session."""
        self._requests.put(None)

    def cancel(self) -> None:
        """Break the stream; the session stays on the server, detached and resumable."""
        self._call.cancel()
        self._requests.put(None)

    def __iter__(self) -> Iterator[pb.TrackResponse]:
        """Every raw ``pb.TrackResponse`` after `opened`, in order; raises grpc.RpcError on an
        error end (``InstanceLost`` when a proxy reset the stream because its instance died)."""
        try:
            for response in self._call:
                self._note(response)
                yield response
        except grpc.RpcError as err:
            mapped = from_proxy_reset(err)
            if mapped is err:
                raise
            raise mapped from err
        finally:
            self._requests.put(None)  # the stream is over: release the request thread

    def estimates(self) -> Iterator[Estimate]:
        """The estimates as ``localizer.Estimate`` (``.raw``: the message); rejections and
        gaps go to .rejected / .gaps."""
        for response in self:
            estimate = self._sort_estimate(response)
            if estimate is not None:
                yield estimate

    def track_lists(self) -> Iterator[pb.TrackList]:
        """Detection sessions: the ``pb.TrackList`` responses only; rejections go to .rejected."""
        for response in self:
            tracks = self._sort_tracks(response)
            if tracks is not None:
                yield tracks

    def code(self) -> grpc.StatusCode:
        """The stream's final grpc.StatusCode (blocks until it ends); UNAVAILABLE for a
        proxy's reset after its instance died."""
        code = self._call.code()
        return grpc.StatusCode.UNAVAILABLE if is_proxy_reset(code, self._call.details()) else code

    def __enter__(self) -> TrackSession:
        return self

    def __exit__(self, *exc) -> bool:
        self.cancel() if exc[0] is not None else self.close()
        return False


def locate_request(config: pb.SessionConfig, samples: npt.ArrayLike,
                   encoding: str) -> pb.LocateRequest:
    count = len(config.array.sensors_m) or None
    return pb.LocateRequest(config=config, block=sample_block(1, samples, channel_count=count,
                                                              encoding=encoding))


def locate(channel: grpc.Channel, config: pb.SessionConfig, samples: npt.ArrayLike, *,
           encoding: str = "float", session_key: str | None = None,
           timeout: float | None = None) -> Fix:
    """One-shot TDOAs and multilateration fix of one block (channels, samples). No session
    is created."""
    metadata = [(SESSION_KEY_METADATA, session_key)] if session_key else None
    response = pb_grpc.LocalizerStub(channel).Locate(locate_request(config, samples, encoding),
                                                     metadata=metadata, timeout=timeout)
    return Fix.from_proto(response)


def list_sessions(channel: grpc.Channel, *, timeout: float | None = None) -> list[pb.SessionInfo]:
    """The sessions the server holds (attached or detached): a list of ``pb.SessionInfo``."""
    response = pb_grpc.LocalizerStub(channel).ListSessions(pb.ListSessionsRequest(),
                                                            timeout=timeout)
    return list(response.sessions)


def close_session(channel: grpc.Channel, session_id: str, resume_token: str, *,
                  session_key: str | None = None,
                  timeout: float | None = None) -> pb.CloseSessionResponse:
    """End a session now (its stream, if any, ends CANCELLED). PERMISSION_DENIED with the
    wrong token, NOT_FOUND if unknown."""
    metadata = [(SESSION_KEY_METADATA, session_key)] if session_key else None
    return pb_grpc.LocalizerStub(channel).CloseSession(
        pb.CloseSessionRequest(session_id=session_id, resume_token=resume_token),
        metadata=metadata, timeout=timeout)
