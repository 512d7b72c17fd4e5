"""What the synchronous and the asyncio Track sessions share: the bookkeeping of one Track
stream (opened, sequence numbers, rejections, gaps, the last frame received), building its
requests, and reading a proxy's reset as the loss of a server instance.

Kept apart so that ``session.TrackSession`` and ``aio.TrackSession`` differ only in how
they wait (threads and a request queue, or coroutines on a grpc.aio call)."""
from __future__ import annotations

import uuid

import grpc
import numpy.typing as npt

from ._stubs import pb
from .blocks import sample_block
from .estimates import Estimate

__all__ = ["InstanceLost", "from_proxy_reset"]


class InstanceLost(grpc.RpcError):
    """The server instance behind a proxy died under a call: code() is UNAVAILABLE, as a
    direct connection reports it; ``cause`` is the proxy's reset as gRPC reported it."""

    def __init__(self, cause: grpc.RpcError):
        super().__init__(cause)
        self.cause = cause

    def code(self) -> grpc.StatusCode:
        return grpc.StatusCode.UNAVAILABLE

    def details(self) -> str:
        return ("the server instance behind the proxy is gone (the proxy reset the stream: "
                f"{self.cause.details()})")

    def initial_metadata(self):
        return self.cause.initial_metadata()

    def trailing_metadata(self):
        return self.cause.trailing_metadata()

    def __str__(self) -> str:
        return f"UNAVAILABLE: {self.details()}"


def is_proxy_reset(code, details) -> bool:
    # Our server always ends a call with a status; an HTTP/2 reset with INTERNAL_ERROR (2)
    # comes from a proxy whose upstream connection broke.
    return code == grpc.StatusCode.INTERNAL and "RST_STREAM with error code 2" in (details or "")


def from_proxy_reset(err: grpc.RpcError) -> grpc.RpcError:
    """``err`` (a grpc.RpcError) as ``InstanceLost`` when it is a proxy's reset of a stream
    whose instance died, else ``err`` itself."""
    try:
        code, details = err.code(), err.details()
    except Exception:  # an RpcError without a status (e.g. raised before the call started)
        return err
    return InstanceLost(err) if is_proxy_reset(code, details) else err


def resume_request(session_id: str, resume_token: str,
                   last_frame_received: int | None) -> pb.ResumeSession:
    """``last_frame_received``: frame_index of the last estimate the client holds; None when
    it holds none (sent as ``received_none``: the server sends every estimate it still has,
    frame 0 first; last_frame_received=0 would mean "frame 0 received")."""
    req = pb.ResumeSession(session_id=session_id, resume_token=resume_token)
    if last_frame_received is not None:
        req.last_frame_received = last_frame_received
    else:
        req.received_none = True
    return req


class StreamState:
    """The client side of one Track stream, without any I/O.

    Attributes: ``opened`` (pb.SessionOpened), ``session_id``, ``resume_token``,
    ``session_key`` (metadata x-localizer-session-key on this and every resumed stream),
    ``channel_count`` (the array's sensors; 0 for a detection session), ``next_sequence``
    (what ``send`` uses next), ``last_frame_received`` (frame_index of the last estimate
    read, or None), ``rejected`` and ``gaps`` (the BlockRejected and SequenceGap responses
    the estimate iterators skipped)."""

    def _start(self, config: pb.SessionConfig | None, resume: pb.ResumeSession | None,
               session_key: str | None) -> pb.TrackRequest:
        """Sets the attributes known before the stream opens; returns its first request."""
        if (config is None) == (resume is None):
            raise ValueError("give exactly one of config (open) and resume")
        self.session_key = session_key or (resume.session_id if resume is not None
                                           else config.label or uuid.uuid4().hex)
        self.last_frame_received = None
        if resume is not None and resume.HasField("last_frame_received"):
            self.last_frame_received = resume.last_frame_received
        self.rejected: list[pb.BlockRejected] = []
        self.gaps: list[pb.SequenceGap] = []
        return pb.TrackRequest(open=config) if config is not None else pb.TrackRequest(resume=resume)

    def _opened(self, first: pb.TrackResponse | None) -> bool:
        """Takes the stream's first response; False when it is not ``opened``."""
        if first is None or first.WhichOneof("kind") != "opened":
            return False
        self.opened = first.opened
        self.session_id = self.opened.session_id
        self.resume_token = self.opened.resume_token
        self.channel_count = len(self.opened.effective_config.array.sensors_m)
        self.next_sequence = (self.opened.last_sequence + 1
                              if self.opened.HasField("last_sequence") else 1)
        return True

    def _block_request(self, samples: npt.ArrayLike, sequence: int | None,
                       encoding: str) -> pb.TrackRequest:
        """The request carrying ``samples`` (channels, samples), checked against the array's
        channel count (ValueError); advances ``next_sequence``."""
        sequence = self.next_sequence if sequence is None else sequence
        block = sample_block(sequence, samples, channel_count=self.channel_count or None,
                             encoding=encoding)
        return self._raw_block_request(block)

    def _raw_block_request(self, block: pb.SampleBlock) -> pb.TrackRequest:
        self.next_sequence = block.sequence + 1
        return pb.TrackRequest(block=block)

    def _note(self, response: pb.TrackResponse) -> None:
        if response.WhichOneof("kind") == "estimate":
            self.last_frame_received = response.estimate.frame_index

    def _sort_estimate(self, response: pb.TrackResponse) -> Estimate | None:
        """The estimate a response holds, or None (rejections and gaps are recorded)."""
        kind = response.WhichOneof("kind")
        if kind == "estimate":
            return Estimate.from_proto(response.estimate)
        if kind == "rejected":
            self.rejected.append(response.rejected)
        elif kind == "gap":
            self.gaps.append(response.gap)
        return None

    def _sort_tracks(self, response: pb.TrackResponse) -> pb.TrackList | None:
        kind = response.WhichOneof("kind")
        if kind == "tracks":
            return response.tracks
        if kind == "rejected":
            self.rejected.append(response.rejected)
        return None
