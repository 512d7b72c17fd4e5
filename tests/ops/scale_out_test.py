"""Session-affine scale-out: three localizer-server instances behind nginx.

deploy/nginx/localizer.conf (rendered with this run's ports) routes every call by consistent
hashing of the metadata key x-localizer-session-key. The test, over loopback:
  1. opens SESSIONS Track streams through nginx, each with its own session key, and streams
     blocks of a synthetic recording on each;
  2. asks each instance directly (ListSessions, not through nginx) which sessions it holds:
     every session lives on exactly one instance and each instance holds at least 2;
     a ListSessions through nginx with a session's key reaches that session's instance;
  3. cancels one stream, waits until its session is detached, resumes it through nginx with
     its token and the same key, and checks that it is the same instance and estimates go on
     after the last frame received;
  4. SIGKILLs one instance (a crash): the streams of its sessions end with UNAVAILABLE, as
     does a stream opened straight to that instance for comparison. Through nginx gRPC
     itself sees the proxy's reset (INTERNAL "Received RST_STREAM with error code 2": stock
     nginx cannot send trailers for a dead upstream); the client library reads that as
     UNAVAILABLE (localizer_client.InstanceLost, C++ client::FromProxyReset) and the test
     checks it did. The streams on the other two keep producing estimates; a resume of a
     lost session through nginx fails (UNAVAILABLE or NOT_FOUND), it never lands quietly
     elsewhere; a new session with a lost key opens on a live instance.
  5. SIGTERMs a second instance (what Kubernetes sends): the server drains, and its streams
     end with the server's own UNAVAILABLE status, carried through nginx as real trailers
     (no mapping involved); the last instance's streams go on and end OK when half-closed.

Environment (set by tests/ops/scale_out.cmake):
  LOCALIZER_SERVER         the localizer-server binary
  LOCALIZER_PY_GEN         the generated stubs (<build>/clients/python/gen)
  LOCALIZER_PY_CLIENT_DIR  the client library (<build>/clients/python)
  LOCALIZER_NGINX          optional: the nginx binary (default: nginx on PATH or /usr/sbin)
Skips, with the reason printed, when nginx or the server binary is missing.
"""
import json
import os
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import threading
import time
import unittest
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]
CLIENT_DIR = os.environ.get("LOCALIZER_PY_CLIENT_DIR") or str(REPO / "clients" / "python")
sys.path.insert(0, CLIENT_DIR)

import grpc  # noqa: E402

import localizer_client as lc  # noqa: E402
from localizer_client import synth  # noqa: E402

SERVER = os.environ.get("LOCALIZER_SERVER", "")
NGINX = (os.environ.get("LOCALIZER_NGINX") or shutil.which("nginx")
         or shutil.which("nginx", path="/usr/sbin:/sbin") or "")
CONF_TEMPLATE = REPO / "deploy" / "nginx" / "localizer.conf"

INSTANCES = 3
SESSIONS = 30          # ring shares vary with the ports; 30 keys make "each instance >= 2" sure
BLOCK_PERIOD_S = 0.2   # per session; the server does not care about real time
FS_HZ = 44100.0
SOUND_SPEED_MPS = 1500.0
FRAME, HOP, BLOCK = 4096, 2048, 4096
SENSORS_M = synth.tetrahedron(edge_m=1.5)
_, TDOA_SAMPLES = synth.source_with_integer_tdoas(SENSORS_M, (2.5, 1.5, -1.0),
                                                  SOUND_SPEED_MPS, FS_HZ)
N_BLOCKS = 21  # periodic recording: block k follows block k-1 for any k (mod N_BLOCKS)
AUDIO = synth.broadband_at_sensors(TDOA_SAMPLES, N_BLOCKS * BLOCK, FS_HZ,
                                   band_hz=(200.0, 8000.0), snr_db=20.0, seed=7)
BLOCKS = [lc.sample_block(0, AUDIO[k * BLOCK:(k + 1) * BLOCK]) for k in range(N_BLOCKS)]


def config(label):
    return lc.session_config(SENSORS_M, FS_HZ, sound_speed_mps=SOUND_SPEED_MPS,
                             frame_samples=FRAME, hop_samples=HOP, band_hz=(200.0, 8000.0),
                             particles=1024, seed=1, label=label)


def free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def wait_until(predicate, timeout_s, what):
    deadline = time.monotonic() + timeout_s
    while not predicate():
        if time.monotonic() > deadline:
            raise AssertionError(f"timed out after {timeout_s} s waiting for {what}")
        time.sleep(0.05)


class Stream:
    """One Track stream through nginx: a thread sends blocks every BLOCK_PERIOD_S, another
    reads estimates; `code` is the final status once the stream is over."""

    def __init__(self, session):
        self.session = session
        self.estimates = 0
        self.last_frame = None
        self.code = None          # grpc.StatusCode once ended
        self.details = ""
        self.error = None         # the grpc.RpcError the stream ended with, if any
        self._stop = threading.Event()
        self._ended = threading.Event()
        self._lock = threading.Lock()
        threading.Thread(target=self._read, daemon=True).start()
        threading.Thread(target=self._send, daemon=True).start()

    def _send(self):
        while not self._stop.is_set() and not self._ended.is_set():
            seq = self.session.next_sequence
            block = lc.pb.SampleBlock()
            block.CopyFrom(BLOCKS[(seq - 1) % N_BLOCKS])
            block.sequence = seq
            self.session.send_block(block)
            self._stop.wait(BLOCK_PERIOD_S)

    def _read(self):
        try:
            for estimate in self.session.estimates():
                with self._lock:
                    self.estimates += 1
                    self.last_frame = estimate.frame_index
            code, details = grpc.StatusCode.OK, ""
        except grpc.RpcError as err:
            code, details = err.code(), err.details()
            self.error = err
        self.code, self.details = code, details
        self._ended.set()

    def count(self):
        with self._lock:
            return self.estimates

    def ended(self, timeout=None):
        return self._ended.wait(timeout)

    def close(self):
        """Stop sending and half-close (the server drains and ends the stream OK)."""
        self._stop.set()
        self.session.close()

    def cancel(self):
        """Stop sending and break the stream (the session stays, detached)."""
        self._stop.set()
        self.session.cancel()


@unittest.skipUnless(NGINX and os.access(NGINX, os.X_OK),
                     "nginx is not installed (Debian: apt-get install nginx-light)")
@unittest.skipUnless(SERVER and os.access(SERVER, os.X_OK),
                     f"no localizer-server binary (LOCALIZER_SERVER={SERVER!r})")
class ScaleOutTest(unittest.TestCase):
    def setUp(self):
        self.tmp = Path(tempfile.mkdtemp(prefix="localizer-scaleout-"))
        # nginx started as root runs its workers as an unprivileged user: let them in.
        os.chmod(self.tmp, 0o755)
        self.procs, self.logs, self.channels = [], [], []
        self.addCleanup(self._cleanup)
        self.servers = [self._start_server(i) for i in range(INSTANCES)]  # (proc, "host:port")
        self.direct = [self._channel(target) for _, target in self.servers]
        self.proxy_target = self._start_nginx()
        self.proxy = self._channel(self.proxy_target)

    # -- processes ------------------------------------------------------------------------

    def _log(self, name):
        log = open(self.tmp / f"{name}.log", "wb")
        self.logs.append(log)
        return log

    def _start_server(self, i):
        ready = self.tmp / f"ready-{i}.json"
        proc = subprocess.Popen(
            [SERVER, "--listen", "127.0.0.1:0", "--metrics-listen", "", "--ready-file", str(ready),
             "--workers", "2", "--session-ttl", "120", "--log-level", "warn"],
            stdout=self._log(f"server-{i}"), stderr=subprocess.STDOUT)
        self.procs.append(proc)
        wait_until(lambda: ready.exists() or proc.poll() is not None, 30, f"server {i} ready")
        if proc.poll() is not None:
            self.fail(f"server {i} exited with {proc.returncode}:\n{self._tail(f'server-{i}')}")
        port = json.loads(ready.read_text())["grpc_port"]
        return proc, f"127.0.0.1:{port}"

    def _start_nginx(self):
        for d in ("logs", "temp"):
            (self.tmp / d).mkdir()
        backends = " ".join(f"server {target};" for _, target in self.servers)
        for attempt in range(5):  # the free port may be taken between probe and bind
            listen = f"127.0.0.1:{free_port()}"
            conf = self.tmp / "localizer.conf"
            conf.write_text(CONF_TEMPLATE.read_text().replace("@LISTEN@", listen)
                            .replace("@BACKENDS@", backends))
            proc = subprocess.Popen(
                [NGINX, "-e", "stderr", "-p", f"{self.tmp}/", "-c", str(conf), "-g",
                 f"daemon off; pid {self.tmp}/nginx.pid; error_log stderr warn;"],
                stdout=self._log(f"nginx-{attempt}"), stderr=subprocess.STDOUT)
            host, port = listen.rsplit(":", 1)

            def listening():
                try:
                    socket.create_connection((host, int(port)), timeout=0.2).close()
                    return True
                except OSError:
                    return proc.poll() is not None
            wait_until(listening, 10, "nginx listening")
            if proc.poll() is None:
                self.procs.append(proc)
                self.nginx = proc
                return listen
        self.fail(f"nginx did not start:\n{self._tail('nginx-4')}")

    def _channel(self, target):
        channel = lc.connect(target)
        self.channels.append(channel)
        grpc.channel_ready_future(channel).result(timeout=10)
        return channel

    def _tail(self, name):
        for log in self.logs:
            log.flush()
        path = self.tmp / f"{name}.log"
        return path.read_bytes().decode(errors="replace")[-3000:] if path.exists() else ""

    def _cleanup(self):
        for channel in self.channels:
            channel.close()
        for proc in self.procs:
            if proc.poll() is None:
                proc.send_signal(signal.SIGTERM if proc is not getattr(self, "nginx", None)
                                 else signal.SIGQUIT)
        for proc in self.procs:
            try:
                proc.wait(timeout=15)
            except subprocess.TimeoutExpired:
                proc.kill()
                proc.wait()
        for log in self.logs:
            log.close()
        if os.environ.get("LOCALIZER_KEEP_TMP"):
            print(f"kept {self.tmp}", file=sys.stderr)
        else:
            shutil.rmtree(self.tmp, ignore_errors=True)

    # -- helpers --------------------------------------------------------------------------

    def placement(self, dead=()):
        """{session_id: [instance index, ...]} and {session_id: SessionInfo}, asked directly
        (instances in `dead` are not asked)."""
        where, infos = {}, {}
        for i, channel in enumerate(self.direct):
            if i in dead:
                continue
            for info in lc.list_sessions(channel, timeout=10):
                where.setdefault(info.session_id, []).append(i)
                infos[info.session_id] = info
        return where, infos

    # -- the test -------------------------------------------------------------------------

    def test_sessions_spread_resume_and_instance_loss(self):
        t0 = time.monotonic()
        # 1. Sessions through nginx, one key each.
        streams = {}
        for k in range(SESSIONS):
            key = f"array-{k:02d}"
            session = lc.TrackSession(self.proxy, config(key), session_key=key, timeout=120)
            streams[session.session_id] = Stream(session)
        for stream in streams.values():
            wait_until(lambda: stream.count() >= 3 or stream.ended(0), 30, "three estimates")
            self.assertIsNone(stream.code, f"stream ended early: {stream.code} {stream.details}")

        # 2. Where did they land? Each on exactly one instance; every instance holds some.
        where, infos = self.placement()
        self.assertEqual(set(where), set(streams), "ListSessions over all instances")
        for session_id, instances in where.items():
            self.assertEqual(len(instances), 1, f"{session_id} on instances {instances}")
            self.assertEqual(infos[session_id].label, streams[session_id].session.session_key)
        owner = {session_id: instances[0] for session_id, instances in where.items()}
        per_instance = [sorted(s for s, i in owner.items() if i == n) for n in range(INSTANCES)]
        counts = [len(s) for s in per_instance]
        print(f"\nsessions per instance: {counts}", file=sys.stderr)
        for n, count in enumerate(counts):
            self.assertGreaterEqual(count, 2, f"instance {n} holds {count} of {SESSIONS}: {counts}")
        # A unary call with a session's key reaches that session's instance too.
        for session_id in list(streams)[:6]:
            key = streams[session_id].session.session_key
            listed = lc.pb_grpc.LocalizerStub(self.proxy).ListSessions(
                lc.pb.ListSessionsRequest(), metadata=[(lc.SESSION_KEY_METADATA, key)],
                timeout=10)
            self.assertIn(session_id, {s.session_id for s in listed.sessions}, key)

        # 3. Break one stream and resume its session through nginx with the same key.
        victim_instance = 0
        survivors = [n for n in range(INSTANCES) if n != victim_instance]
        resumed_id = per_instance[survivors[0]][0]
        old = streams[resumed_id]
        old.cancel()
        self.assertTrue(old.ended(10), "cancelled stream did not end")
        self.assertEqual(old.code, grpc.StatusCode.CANCELLED)
        wait_until(lambda: not self.placement()[1][resumed_id].attached, 10,
                   "the cancelled session to be detached")
        last = old.session.last_frame_received
        resumed = old.session.reattach(self.proxy, timeout=120)
        self.assertEqual(resumed.session_id, resumed_id)
        self.assertEqual(resumed.session_key, old.session.session_key)
        stream = Stream(resumed)
        streams[resumed_id] = stream
        wait_until(lambda: stream.count() >= 2 or stream.ended(0), 30, "estimates after resume")
        self.assertIsNone(stream.code, f"resumed stream ended: {stream.code} {stream.details}")
        self.assertGreater(stream.last_frame, last)
        where, infos = self.placement()
        self.assertEqual(where[resumed_id], [owner[resumed_id]], "resumed on another instance")
        self.assertTrue(infos[resumed_id].attached)
        print(f"resumed {resumed_id} on instance {owner[resumed_id]} after frame {last}; "
              f"estimates go on at frame {stream.last_frame}", file=sys.stderr)

        # 4. Kill one instance: its streams fail, the others keep estimating. For comparison,
        # one more stream straight to that instance (no nginx in between).
        direct = Stream(lc.TrackSession(self.direct[victim_instance], config("direct"),
                                        session_key="direct", timeout=120))
        wait_until(lambda: direct.count() >= 1 or direct.ended(0), 30, "a direct estimate")
        before = {s: streams[s].count() for s in streams}
        proc, _ = self.servers[victim_instance]
        proc.send_signal(signal.SIGKILL)
        proc.wait(timeout=10)
        lost = per_instance[victim_instance]
        kept = [s for s in streams if owner[s] != victim_instance]
        for session_id in lost:
            self.assertTrue(streams[session_id].ended(20), f"{session_id}: stream still open")
        lost_codes = {s: (streams[s].code, streams[s].details) for s in lost}
        print(f"killed instance {victim_instance}: its {len(lost)} streams ended with "
              f"{sorted({c.name for c, _ in lost_codes.values()})} "
              f"({next(iter(lost_codes.values()))[1]!r})", file=sys.stderr)
        self.assertTrue(direct.ended(20), "direct stream still open")
        print(f"the direct stream to the killed instance: {direct.code.name} "
              f"({direct.details!r})", file=sys.stderr)
        self.assertEqual(direct.code, grpc.StatusCode.UNAVAILABLE, direct.details)
        for session_id, (code, details) in lost_codes.items():
            self.assertEqual(code, grpc.StatusCode.UNAVAILABLE, f"{session_id}: {details}")
            self.assertIsInstance(streams[session_id].error, lc.InstanceLost, session_id)
            self.assertEqual(streams[session_id].session.code(), grpc.StatusCode.UNAVAILABLE)
        time.sleep(2.0)
        after = {s: streams[s].count() for s in kept}
        for session_id in kept:
            self.assertIsNone(streams[session_id].code,
                              f"{session_id} on a live instance ended: "
                              f"{streams[session_id].code} {streams[session_id].details}")
            self.assertGreater(after[session_id], before[session_id],
                               f"{session_id}: no estimates since the kill")
        # A resume of a lost session does not quietly succeed anywhere.
        gone = streams[lost[0]].session
        with self.assertRaises(grpc.RpcError) as caught:
            gone.reattach(self.proxy, timeout=10)
        print(f"resume of a lost session: {caught.exception.code().name} "
              f"({caught.exception.details()!r})", file=sys.stderr)
        self.assertIn(caught.exception.code(),
                      (grpc.StatusCode.UNAVAILABLE, grpc.StatusCode.NOT_FOUND))

        # A new session with that key opens on a live instance: nginx has taken the dead one
        # out of its ring (max_fails 1, fail_timeout 10 s).
        fresh = lc.TrackSession(self.proxy, config("fresh"), session_key=gone.session_key,
                                timeout=30)
        where, _ = self.placement(dead=(victim_instance,))
        self.assertIn(where.get(fresh.session_id), [[n] for n in survivors])
        print(f"new session with the lost key {gone.session_key!r} opened on instance "
              f"{where[fresh.session_id][0]}", file=sys.stderr)
        fresh.close()
        list(fresh)

        # 5. SIGTERM a second instance: it drains and ends its streams with its own
        # UNAVAILABLE, which nginx passes on as trailers.
        drained_instance, last_instance = survivors
        drained = [s for s in kept if owner[s] == drained_instance]
        kept = [s for s in kept if owner[s] == last_instance]
        before = {s: streams[s].count() for s in kept}
        proc, _ = self.servers[drained_instance]
        proc.send_signal(signal.SIGTERM)
        self.assertEqual(proc.wait(timeout=30), 0, self._tail(f"server-{drained_instance}"))
        for session_id in drained:
            stream = streams[session_id]
            self.assertTrue(stream.ended(20), f"{session_id}: stream still open after SIGTERM")
            self.assertEqual(stream.code, grpc.StatusCode.UNAVAILABLE, stream.details)
            self.assertNotIsInstance(stream.error, lc.InstanceLost, stream.details)
            self.assertIn("shutting down", stream.details)
        print(f"SIGTERM to instance {drained_instance}: its {len(drained)} streams ended with "
              f"the server's UNAVAILABLE ({streams[drained[0]].details!r})", file=sys.stderr)
        time.sleep(1.0)
        for session_id in kept:
            self.assertIsNone(streams[session_id].code, f"{session_id} on the last instance ended")
            self.assertGreater(streams[session_id].count(), before[session_id], session_id)

        # The survivors finish cleanly.
        for session_id in kept:
            streams[session_id].close()
        for session_id in kept:
            self.assertTrue(streams[session_id].ended(30), f"{session_id} did not finish")
            self.assertEqual(streams[session_id].code, grpc.StatusCode.OK,
                             f"{session_id}: {streams[session_id].details}")
        print(f"total {time.monotonic() - t0:.1f} s", file=sys.stderr)


if __name__ == "__main__":
    unittest.main(verbosity=2)
