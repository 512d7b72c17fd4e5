"""The client for asyncio (grpc.aio): the synchronous client's calls as coroutines.

    import localizer, localizer.aio
    async with localizer.aio.connect("127.0.0.1:50051") as channel:
        session = await localizer.aio.TrackSession.open(channel, config)
        await session.send(block)                      # (channels, samples) float32/64
        await session.close()                          # half-close
        async for estimate in session.estimates():     # localizer.Estimate
            print(estimate.frame_index, estimate.position_m)

Same names, arguments, attributes and errors as ``localizer.TrackSession`` / ``locate`` /
``list_sessions`` / ``close_session``, except that opening is ``await TrackSession.open``
(a constructor cannot wait) and every call that waits is awaited. Sending and reading may run
in different tasks; ``send`` waits while gRPC flow control holds the block, so a task that
only sends cannot outrun the server.
"""
from __future__ import annotations

import asyncio
from typing import AsyncIterator

import grpc
import grpc.aio
import numpy.typing as npt

from ._stubs import pb, pb_grpc
from ._track import StreamState, from_proxy_reset, is_proxy_reset, resume_request
from .connection import SESSION_KEY_METADATA, auth_metadata, resolve_token, tls_credentials
from .estimates import Estimate, Fix
from .session import locate_request

__all__ = ["connect", "TrackSession", "locate", "list_sessions", "close_session"]


class _BearerToken:
    """Adds ``authorization: Bearer TOKEN`` to every call (over TLS or plaintext). One
    interceptor object per call kind: grpc.aio 1.51 files an interceptor under the first kind
    it implements only."""

    def __init__(self, token: str):
        self._pair = auth_metadata(token)

    def _details(self, d):
        metadata = grpc.aio.Metadata(*tuple(d.metadata or ()), self._pair)
        return grpc.aio.ClientCallDetails(d.method, d.timeout, metadata, d.credentials,
                                          d.wait_for_ready)


class _UnaryUnaryToken(_BearerToken, grpc.aio.UnaryUnaryClientInterceptor):
    async def intercept_unary_unary(self, continuation, details, request):
        return await continuation(self._details(details), request)


class _UnaryStreamToken(_BearerToken, grpc.aio.UnaryStreamClientInterceptor):
    async def intercept_unary_stream(self, continuation, details, request):
        return await continuation(self._details(details), request)


class _StreamUnaryToken(_BearerToken, grpc.aio.StreamUnaryClientInterceptor):
    async def intercept_stream_unary(self, continuation, details, request_iterator):
        return await continuation(self._details(details), request_iterator)


class _StreamStreamToken(_BearerToken, grpc.aio.StreamStreamClientInterceptor):
    async def intercept_stream_stream(self, continuation, details, request_iterator):
        return await continuation(self._details(details), request_iterator)


def connect(target: str, *, options=(), credentials: grpc.ChannelCredentials | None = None,
            tls_ca: str | None = None, tls_cert: str | None = None, tls_key: str | None = None,
            token: str | None = None, token_file: str | None = None) -> grpc.aio.Channel:
    """A grpc.aio channel to ``target``; arguments as ``localizer.connect``. Make it inside
    the event loop that uses it; ``async with`` (or ``await channel.close()``) closes it."""
    if credentials is None:
        credentials = tls_credentials(tls_ca, tls_cert, tls_key)
    token = resolve_token(token, token_file)
    interceptors = None
    if token is not None:
        interceptors = [kind(token) for kind in (_UnaryUnaryToken, _UnaryStreamToken,
                                                 _StreamUnaryToken, _StreamStreamToken)]
    if credentials is not None:
        return grpc.aio.secure_channel(target, credentials, options=list(options),
                                       interceptors=interceptors)
    return grpc.aio.insecure_channel(target, options=list(options), interceptors=interceptors)


class TrackSession(StreamState):
    """One Track stream on a grpc.aio channel; see ``localizer.TrackSession``. Made by
    ``await TrackSession.open(...)`` or ``await TrackSession.resume(...)``."""

    @classmethod
    async def _create(cls, channel: grpc.aio.Channel, config: pb.SessionConfig | None,
                      resume: pb.ResumeSession | None, session_key: str | None,
                      timeout: float | None) -> TrackSession:
        self = cls()
        first_request = self._start(config, resume, session_key)
        self._channel = channel
        self._call = pb_grpc.LocalizerStub(channel).Track(
            metadata=((SESSION_KEY_METADATA, self.session_key),), timeout=timeout)
        try:
            await self._write(first_request)
            first = await self._read()
        except grpc.RpcError as err:
            mapped = from_proxy_reset(err)
            if mapped is err:
                raise
            raise mapped from err
        if not self._opened(first):
            self._call.cancel()
            raise RuntimeError(f"Track: expected `opened` first, got {first!r}")
        return self

    @classmethod
    async def open(cls, channel: grpc.aio.Channel, config: pb.SessionConfig, *,
                   session_key: str | None = None, timeout: float | None = None) -> TrackSession:
        """Open a session; raises grpc.RpcError if the server refuses it."""
        return await cls._create(channel, config, None, session_key, timeout)

    @classmethod
    async def resume(cls, channel: grpc.aio.Channel, session_id: str, resume_token: str, *,
                     last_frame_received: int | None = None, session_key: str | None = None,
                     timeout: float | None = None) -> TrackSession:
        """Resume a detached session; see ``localizer.TrackSession.resume``."""
        request = resume_request(session_id, resume_token, last_frame_received)
        return await cls._create(channel, None, request, session_key, timeout)

    async def reattach(self, channel: grpc.aio.Channel | None = None, *,
                       timeout: float | None = None) -> TrackSession:
        """A new session object resuming this one (same session key)."""
        return await type(self).resume(channel or self._channel, self.session_id,
                                       self.resume_token,
                                       last_frame_received=self.last_frame_received,
                                       session_key=self.session_key, timeout=timeout)

    async def _read(self) -> pb.TrackResponse | None:
        """The next response, None at the end of the stream."""
        try:
            response = await self._call.read()
        except StopAsyncIteration:  # how an intercepted call (connect(token=...)) says EOF
            return None
        return None if response is grpc.aio.EOF else response

    async def _write(self, request: pb.TrackRequest) -> None:
        try:
            await self._call.write(request)
        except asyncio.InvalidStateError:
            # A call that went through an interceptor (connect(token=...)) says "RPC already
            # finished" where a plain call raises its status: raise the status here too.
            if self._call.done():
                code = await self._call.code()
                if code != grpc.StatusCode.OK:
                    raise from_proxy_reset(grpc.aio.AioRpcError(
                        code, await self._call.initial_metadata(),
                        await self._call.trailing_metadata(), await self._call.details()))
            raise

    async def send(self, samples: npt.ArrayLike, *, sequence: int | None = None,
                   encoding: str = "float") -> int:
        """Send one block (channels, samples); returns its sequence number. ValueError for a
        bad block, as ``localizer.TrackSession.send``."""
        request = self._block_request(samples, sequence, encoding)
        await self._write(request)
        return request.block.sequence

    async def send_block(self, block: pb.SampleBlock) -> None:
        """Send a ready ``pb.SampleBlock`` as is."""
        await self._write(self._raw_block_request(block))

    async def send_imu(self, batch: pb.ImuBatch) -> None:
        """Send a ``pb.ImuBatch`` (moving-array sessions)."""
        await self._write(pb.TrackRequest(imu=batch))

    async def send_scan(self, scan_message: pb.Scan) -> None:
        """Send a ``pb.Scan`` (detection sessions); answered by a ``tracks`` response."""
        await self._write(pb.TrackRequest(scan=scan_message))

    async def close(self) -> None:
        """Half-close: no more blocks; the server drains, ends OK and closes the session."""
        await self._call.done_writing()

    def cancel(self) -> None:
        """Break the stream; the session stays on the server, detached and resumable."""
        self._call.cancel()

    async def _responses(self) -> AsyncIterator[pb.TrackResponse]:
        try:
            while True:
                response = await self._read()
                if response is None:
                    return
                self._note(response)
                yield response
        except grpc.RpcError as err:
            mapped = from_proxy_reset(err)
            if mapped is err:
                raise
            raise mapped from err

    def __aiter__(self) -> AsyncIterator[pb.TrackResponse]:
        """Every raw ``pb.TrackResponse`` after `opened` (``async for r in session``)."""
        return self._responses()

    async def estimates(self) -> AsyncIterator[Estimate]:
        """The estimates as ``localizer.Estimate``; rejections and gaps go to .rejected / .gaps."""
        async for response in self._responses():
            estimate = self._sort_estimate(response)
            if estimate is not None:
                yield estimate

    async def track_lists(self) -> AsyncIterator[pb.TrackList]:
        """Detection sessions: the ``pb.TrackList`` responses only."""
        async for response in self._responses():
            tracks = self._sort_tracks(response)
            if tracks is not None:
                yield tracks

    async def code(self) -> grpc.StatusCode:
        """The stream's final status code (waits for the end); UNAVAILABLE for a proxy's reset."""
        code = await self._call.code()
        return (grpc.StatusCode.UNAVAILABLE
                if is_proxy_reset(code, await self._call.details()) else code)

    async def __aenter__(self) -> TrackSession:
        return self

    async def __aexit__(self, *exc) -> bool:
        if exc[0] is not None:
            self.cancel()
        else:
            await self.close()
        return False


async def locate(channel: grpc.aio.Channel, config: pb.SessionConfig, samples: npt.ArrayLike, *,
                 encoding: str = "float", session_key: str | None = None,
                 timeout: float | None = None) -> Fix:
    """One-shot TDOAs and fix of one block (channels, samples); see ``localizer.locate``."""
    metadata = ((SESSION_KEY_METADATA, session_key),) if session_key else None
    response = await pb_grpc.LocalizerStub(channel).Locate(
        locate_request(config, samples, encoding), metadata=metadata, timeout=timeout)
    return Fix.from_proto(response)


async def list_sessions(channel: grpc.aio.Channel, *,
                        timeout: float | None = None) -> list[pb.SessionInfo]:
    """The sessions the server holds: a list of ``pb.SessionInfo``."""
    response = await pb_grpc.LocalizerStub(channel).ListSessions(pb.ListSessionsRequest(),
                                                                  timeout=timeout)
    return list(response.sessions)


async def close_session(channel: grpc.aio.Channel, session_id: str, resume_token: str, *,
                        session_key: str | None = None,
                        timeout: float | None = None) -> pb.CloseSessionResponse:
    """End a session now; see ``localizer.close_session``."""
    metadata = ((SESSION_KEY_METADATA, session_key),) if session_key else None
    return await pb_grpc.LocalizerStub(channel).CloseSession(
        pb.CloseSessionRequest(session_id=session_id, resume_token=resume_token),
        metadata=metadata, timeout=timeout)
