#!/usr/bin/python3
"""Load test for the localizer service: N concurrent Track sessions streaming synthetic audio.

    /usr/bin/python3 loadtest.py --target 127.0.0.1:50051 --sessions 300 --duration 30 \
        --rate realtime [--processes 2]

Every session opens a Track stream with a 4-sensor tetrahedral array (edge 1.5 m, sound
speed 1500 m/s, GCC band 200-8000 Hz) and streams a synthetic recording of a broadband source
at a fixed point (integer-sample delays from the geometry, 20 dB SNR, seeded by --seed). The
recording is generated once per process, its blocks are serialised once, and sending a block
only prefixes its sequence number to the ready bytes, so the generator stays cheap beside the
server on the same machine.

  --rate realtime  each session sends one block every block/sample_rate seconds, on an
                   absolute schedule (no drift), sessions staggered over the ramp (or, without
                   a ramp, over one block period)
  --rate max       each session sends as fast as gRPC flow control lets it

Latency of an estimate = the time it was received - the time the block it names (its
`sequence`, the block that completed its frame) was handed to gRPC, as seen by this client
(so it includes the client's own event-loop lag; the progress line shows that lag).

Each second a progress line goes to stderr; at the end a summary goes to stdout, closed by a
line `RESULT {json}` with the same figures. After --duration every stream is half-closed: the
server processes what it accepted, sends the last estimates and ends the stream OK. Ctrl-C
(SIGINT) stops the sending early the same way; the summary is then marked interrupted.

Errors are counted by the status code a stream ended with (UNAVAILABLE, RESOURCE_EXHAUSTED,
...), plus DRAIN_TIMEOUT (no end within --drain-timeout after the half-close), PROTOCOL and
NO_OPENED (the server broke the Track contract) and CLIENT_* (a fault in this script).

Exit status: 0 no errors, no rejections and some estimates, 1 otherwise, 2 usage error.
"""
import argparse
import asyncio
import collections
import math
import multiprocessing
import queue
import signal
import sys
import time

import grpc
import grpc.aio
import numpy as np

import localizer as lc
from localizer import pb, synth
from loadtest_report import Aggregator, print_summary

SOUND_SPEED_MPS = 1500.0
ARRAY_EDGE_M = 1.5
SOURCE_M = (2.5, 1.5, -1.0)  # moved to the nearest point with whole-sample TDOAs
BAND_HZ = (200.0, 8000.0)
SNR_DB = 20.0
TRACK_METHOD = "/localizer.v1.Localizer/Track"
STREAMS_PER_CONNECTION = 100


def parse_args(argv=None):
    p = argparse.ArgumentParser(
        description="Load-test a localizer server with concurrent Track sessions.",
        formatter_class=argparse.ArgumentDefaultsHelpFormatter)
    p.add_argument("--target", required=True, help="server address HOST:PORT")
    lc.add_connect_arguments(p)
    p.add_argument("--sessions", type=int, required=True, help="concurrent Track sessions")
    p.add_argument("--duration", type=float, required=True,
                   help="seconds each session streams (after its start in the ramp)")
    p.add_argument("--rate", choices=("realtime", "max"), required=True,
                   help="realtime: one block per block duration; max: as fast as flow control allows")
    p.add_argument("--channels", type=int, default=4, help="sensors (>= 4; first 4: tetrahedron)")
    p.add_argument("--sample-rate", type=float, default=44100.0, help="Hz")
    p.add_argument("--frame", type=int, default=4096, help="GCC frame, samples")
    p.add_argument("--hop", type=int, default=2048, help="frame advance, samples")
    p.add_argument("--block", type=int, default=4096, help="samples per channel per block")
    p.add_argument("--particles", type=int, default=4096, help="particle filter size")
    p.add_argument("--encoding", choices=("float", "pcm16"), default="float",
                   help="float: SampleBlock.samples; pcm16: SampleBlock.pcm_s16le")
    p.add_argument("--backend", default="auto", help='session backend: "auto", "cpu", "gpu"')
    p.add_argument("--seed", type=int, default=1, help="signal seed; session i uses seed + i")
    p.add_argument("--ramp", type=float, default=0.0,
                   help="seconds over which session starts are spread")
    p.add_argument("--processes", type=int, default=1,
                   help="split the sessions over this many processes (one event loop each)")
    p.add_argument("--connections", type=int, default=0,
                   help=f"gRPC connections per process; 0: one per {STREAMS_PER_CONNECTION} sessions")
    p.add_argument("--signal-seconds", type=float, default=4.0,
                   help="length of the pre-generated recording that every session loops")
    p.add_argument("--drain-timeout", type=float, default=30.0,
                   help="seconds to wait for a stream to end after half-closing it")
    a = p.parse_args(argv)
    checks = [(a.sessions >= 1, "--sessions must be >= 1"),
              (a.duration > 0, "--duration must be > 0"),
              (a.channels >= 4, "--channels must be >= 4"),
              (a.sample_rate > 0, "--sample-rate must be > 0"),
              (a.frame >= 64, "--frame must be >= 64"),
              (1 <= a.hop <= a.frame, "--hop must be in [1, frame]"),
              (a.block >= 1, "--block must be >= 1"),
              (a.particles >= 16, "--particles must be >= 16"),
              (a.ramp >= 0, "--ramp must be >= 0"),
              (1 <= a.processes <= a.sessions, "--processes must be in [1, sessions]"),
              (a.connections >= 0, "--connections must be >= 0"),
              (a.signal_seconds > 0, "--signal-seconds must be > 0"),
              (a.drain_timeout > 0, "--drain-timeout must be > 0")]
    for ok, message in checks:
        if not ok:
            p.error(message)
    return a


def varint(n):
    out = bytearray()
    while n >= 0x80:
        out.append((n & 0x7F) | 0x80)
        n >>= 7
    out.append(n)
    return bytes(out)


class Workload:
    """The synthetic recording, pre-serialised: one SampleBlock body (everything but the
    sequence number) per distinct block, and the open request of each session."""

    def __init__(self, args):
        self.args = args
        self.sensors_m = synth.array_positions(args.channels, ARRAY_EDGE_M)
        self.source_m, tdoa = synth.source_with_integer_tdoas(
            self.sensors_m, SOURCE_M, SOUND_SPEED_MPS, args.sample_rate)
        n_blocks = max(1, math.ceil(args.signal_seconds * args.sample_rate / args.block))
        audio = synth.broadband_at_sensors(tdoa, n_blocks * args.block, args.sample_rate,
                                           band_hz=self.band_hz(), snr_db=SNR_DB, seed=args.seed)
        self.bodies = []
        for k in range(n_blocks):
            chunk = audio[:, k * args.block:(k + 1) * args.block]  # (channels, samples)
            # sequence 0 is not serialised: the body is channel_count + samples only.
            self.bodies.append(lc.sample_block(0, chunk, encoding=args.encoding).SerializeToString())
        check = pb.TrackRequest.FromString(self.block_request(7, 0))
        assert check.block.sequence == 7 and check.block.channel_count == args.channels

    def band_hz(self):
        return (BAND_HZ[0], min(BAND_HZ[1], 0.45 * self.args.sample_rate))

    def open_request(self, i):
        a = self.args
        config = lc.session_config(self.sensors_m, a.sample_rate, sound_speed_mps=SOUND_SPEED_MPS,
                                   frame_samples=a.frame, hop_samples=a.hop,
                                   particles=a.particles, band_hz=self.band_hz(),
                                   seed=a.seed + i, backend=a.backend, label=f"loadtest-{i}")
        return pb.TrackRequest(open=config).SerializeToString()

    def block_request(self, sequence, k):
        """Serialised TrackRequest{block: SampleBlock{sequence, <body k>}}: field 3 (block,
        length-delimited) holding field 1 (sequence, varint) followed by the ready body."""
        body = self.bodies[k]
        seq = varint(sequence)
        return b"".join((b"\x1a", varint(1 + len(seq) + len(body)), b"\x08", seq, body))


class Stats:
    """Counters of one process; snapshot() is what goes to the aggregator."""

    def __init__(self):
        self.started = self.open = self.opened = self.blocks = self.estimates = self.gaps = 0
        self.rejections = collections.Counter()
        self.errors = collections.Counter()
        self.backends = collections.Counter()
        self.latencies = []
        self.window = []
        self.first_send = self.last_send = self.last_estimate = None
        self.behind_max_s = 0.0
        self.loop_lag_s = 0.0
        self.interrupted = False

    def snapshot(self, final=False):
        snap = {k: getattr(self, k) for k in ("started", "open", "opened", "blocks", "estimates",
                                              "gaps", "first_send", "last_send", "last_estimate",
                                              "behind_max_s", "loop_lag_s", "interrupted")}
        snap.update(rejections=dict(self.rejections), errors=dict(self.errors),
                    backends=dict(self.backends), window=np.array(self.window))
        self.window = []
        self.loop_lag_s = 0.0
        if final:
            snap["latencies"] = np.array(self.latencies)
        return snap


class Worker:
    """The sessions of one process, on one asyncio event loop."""

    def __init__(self, args, indices, t0, sink):
        self.args, self.indices, self.t0, self.sink = args, indices, t0, sink
        self.stats = Stats()
        self.workload = Workload(args)
        self.period = args.block / args.sample_rate
        self.stop = None

    def start_time(self, i):
        spread = self.args.ramp if self.args.ramp > 0 else (
            self.period if self.args.rate == "realtime" else 0.0)
        return self.t0 + spread * i / self.args.sessions

    async def run(self):
        loop = asyncio.get_running_loop()
        self.stop = asyncio.Event()
        try:
            loop.add_signal_handler(signal.SIGINT, self.stop.set)
        except (NotImplementedError, RuntimeError):
            pass
        n_conn = self.args.connections or max(1, math.ceil(len(self.indices) / STREAMS_PER_CONNECTION))
        # A local subchannel pool per channel: otherwise identical channels share one connection.
        options = [("grpc.use_local_subchannel_pool", 1)]
        credentials = lc.tls_credentials(self.args.tls_ca, self.args.tls_cert, self.args.tls_key)
        if credentials is not None:
            channels = [grpc.aio.secure_channel(self.args.target, credentials, options=options)
                        for _ in range(n_conn)]
        else:
            channels = [grpc.aio.insecure_channel(self.args.target, options=options)
                        for _ in range(n_conn)]
        # The bearer token rides on each call's metadata (aio channels take no sync interceptors).
        self.auth = ((lc.auth_metadata(lc.read_token_file(self.args.auth_token_file)),)
                     if self.args.auth_token_file else ())
        # Requests go out as ready bytes (no serializer); responses are parsed by protobuf.
        self.track = [ch.stream_stream(TRACK_METHOD, request_serializer=None,
                                       response_deserializer=pb.TrackResponse.FromString)
                      for ch in channels]
        reporter = asyncio.ensure_future(self.report_every_second())
        await asyncio.gather(*(self.session(i, n) for n, i in enumerate(self.indices)))
        reporter.cancel()
        self.stats.interrupted = self.stop.is_set()
        for ch in channels:
            await ch.close()
        return self.stats.snapshot(final=True)

    async def report_every_second(self):
        loop = asyncio.get_running_loop()
        next_t = loop.time() + 1.0
        while True:
            await asyncio.sleep(max(0.0, next_t - loop.time()))
            self.stats.loop_lag_s = max(self.stats.loop_lag_s, loop.time() - next_t)
            next_t += 1.0
            self.sink(self.stats.snapshot())

    async def session(self, i, n):
        loop = asyncio.get_running_loop()
        st, wl = self.stats, self.workload
        start = self.start_time(i)
        await asyncio.sleep(max(0.0, start - loop.time()))
        if self.stop.is_set():
            return
        st.started += 1
        call = self.track[n % len(self.track)](metadata=((lc.SESSION_KEY_METADATA, f"loadtest-{i}"),) + self.auth)
        send_times = []  # send_times[seq - 1]: when block `seq` was handed to gRPC
        opened = cancelled = False
        try:
            await call.write(wl.open_request(i))
            first = await call.read()
            if first is not grpc.aio.EOF and first.WhichOneof("kind") == "opened":
                opened = True
                st.open += 1
                st.opened += 1
                st.backends[first.opened.backend] += 1
                receiver = asyncio.ensure_future(self.receive(call, send_times))
                try:
                    await self.send(call, start, send_times)
                    await call.done_writing()
                except (grpc.aio.AioRpcError, asyncio.InvalidStateError):
                    pass  # the stream ended early; its status is counted below
                try:
                    await asyncio.wait_for(receiver, self.args.drain_timeout)
                except asyncio.TimeoutError:
                    st.errors["DRAIN_TIMEOUT"] += 1
                    call.cancel()
                    cancelled = True
            elif first is not grpc.aio.EOF:
                st.errors["PROTOCOL"] += 1  # something other than `opened` came first
                call.cancel()
                cancelled = True
        except (grpc.aio.AioRpcError, asyncio.InvalidStateError):
            pass
        except Exception as e:  # a client-side fault: counted, the other sessions go on
            st.errors[f"CLIENT_{type(e).__name__}"] += 1
            print(f"loadtest: session {i}: {e!r}", file=sys.stderr)
            call.cancel()
            cancelled = True
        finally:
            if opened:
                st.open -= 1
        code = await call.code()
        if code != grpc.StatusCode.OK and not cancelled:
            st.errors[code.name] += 1
        elif not opened and not cancelled and not self.stop.is_set():
            st.errors["NO_OPENED"] += 1  # the stream ended OK without `opened`

    async def send(self, call, start, send_times):
        loop = asyncio.get_running_loop()
        st, wl = self.stats, self.workload
        realtime = self.args.rate == "realtime"
        end = start + self.args.duration
        n_bodies = len(wl.bodies)
        seq, due = 1, start
        while not self.stop.is_set():
            if realtime:
                if due >= end:
                    break
                if due > loop.time():
                    await asyncio.sleep(due - loop.time())
                st.behind_max_s = max(st.behind_max_s, loop.time() - due)
                due += self.period
            elif loop.time() >= end:
                break
            request = wl.block_request(seq, (seq - 1) % n_bodies)
            now = loop.time()
            send_times.append(now)
            if st.first_send is None:
                st.first_send = now
            await call.write(request)
            st.last_send = now
            st.blocks += 1
            seq += 1

    async def receive(self, call, send_times):
        loop = asyncio.get_running_loop()
        st = self.stats
        try:
            while True:
                response = await call.read()
                if response is grpc.aio.EOF:
                    return
                now = loop.time()
                kind = response.WhichOneof("kind")
                if kind == "estimate":
                    st.estimates += 1
                    st.last_estimate = now
                    seq = response.estimate.sequence
                    if 1 <= seq <= len(send_times):
                        latency = now - send_times[seq - 1]
                        st.latencies.append(latency)
                        st.window.append(latency)
                elif kind == "rejected":
                    st.rejections[response.rejected.reason or response.rejected.code] += 1
                elif kind == "gap":
                    st.gaps += 1
                else:
                    st.errors["PROTOCOL"] += 1
        except grpc.aio.AioRpcError:
            return  # counted by session() from the call's status


def split(args):
    """Session indices per process: i % processes."""
    return [list(range(w, args.sessions, args.processes)) for w in range(args.processes)]


def child_main(args, w, indices, messages, go, t0_value):
    """One process of --processes K: builds its workload, waits for the common start, runs."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # until its own loop handles SIGINT
    worker = Worker(args, indices, 0.0, lambda snap: messages.put(("progress", w, snap)))
    messages.put(("ready", w, None))
    go.wait()
    worker.t0 = t0_value.value
    try:
        messages.put(("final", w, asyncio.run(worker.run())))
    except BaseException as e:  # report and let the parent count it
        messages.put(("failed", w, repr(e)))


def run_in_process(args):
    t0 = time.monotonic()
    agg = Aggregator(args, 1, t0)

    def sink(snap):
        agg.update(0, snap)
        agg.progress()

    worker = Worker(args, list(range(args.sessions)), 0.0, sink)
    worker.t0 = agg.t0 = time.monotonic() + 0.05
    agg.finals[0] = asyncio.run(worker.run())
    return agg, time.monotonic() - agg.t0


def run_in_processes(args):
    ctx = multiprocessing.get_context("spawn")  # no fork after grpc was imported
    messages, go, t0_value = ctx.Queue(), ctx.Event(), ctx.Value("d", 0.0)
    procs = [ctx.Process(target=child_main, args=(args, w, idx, messages, go, t0_value), daemon=True)
             for w, idx in enumerate(split(args))]
    for p in procs:
        p.start()
    stopping = []
    signal.signal(signal.SIGINT, lambda *_: stopping.append(1))  # children drain on SIGINT
    ready = 0
    while ready < len(procs):
        kind, w, payload = messages.get()
        if kind == "ready":
            ready += 1
        elif kind == "failed":
            sys.exit(f"loadtest: process {w} failed: {payload}")
    t0 = time.monotonic() + 0.1
    t0_value.value = t0
    go.set()
    agg = Aggregator(args, len(procs), t0)
    done, next_print = 0, t0 + 1.0
    while done < len(procs):
        try:
            kind, w, payload = messages.get(timeout=max(0.01, next_print - time.monotonic()))
            if kind == "progress":
                agg.update(w, payload)
            elif kind == "final":
                agg.finals[w] = payload
                done += 1
            elif kind == "failed":
                sys.exit(f"loadtest: process {w} failed: {payload}")
        except queue.Empty:
            pass
        if time.monotonic() >= next_print:
            agg.progress()
            next_print += 1.0
    for p in procs:
        p.join()
    return agg, time.monotonic() - t0


def main(argv=None):
    args = parse_args(argv)
    agg, wall_s = run_in_process(args) if args.processes == 1 else run_in_processes(args)
    result = agg.result(wall_s)
    print_summary(result)
    failed = result["errors"] or result["rejections"] or result["estimates"] == 0
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
