"""Calls on a connected channel: a Track stream (``TrackSession``, resumable, with proxy-loss
detection), one-shot ``locate``, and the operator calls ``list_sessions`` / ``close_session``."""
import queue
import uuid

import grpc

from ._stubs import pb, pb_grpc
from .connection import SESSION_KEY_METADATA
from .messages import sample_block

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
