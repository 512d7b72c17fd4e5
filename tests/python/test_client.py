"""The Python client, through its deprecated alias localizer_client (the old (frames,
channels) blocks and raw estimates: scripts written for it must keep working), against a real
localizer-server over loopback. test_package_client tests the package localizer itself.

Environment (set by tests/python/CMakeLists.txt):
  LOCALIZER_PY_CLIENT_DIR  the client package, its stubs and scripts (<build>/clients/python)
  LOCALIZER_SERVER         the localizer-server binary; the server tests skip without it

The synthetic recording: a 1.5 m regular tetrahedron of sensors, sound speed 1500 m/s,
44.1 kHz, a 200-8000 Hz white-noise source 20 dB above independent sensor noise, at the point
near (2.5, 1.5, -1.0) m whose TDOAs are whole samples (6, 16, 38 samples against sensor 0), so
the samples are exactly what the geometry gives there. SyntheticSignalTest checks that claim
independently of the server.
"""
import json
import os
import shutil
import signal
import subprocess
import sys
import tempfile
import threading
import time
import unittest
from pathlib import Path

CLIENT_DIR = os.environ.get("LOCALIZER_PY_CLIENT_DIR") or str(
    Path(__file__).resolve().parents[2] / "clients" / "python")
sys.path.insert(0, CLIENT_DIR)

import grpc  # noqa: E402
import numpy as np  # noqa: E402

import localizer_client as lc  # noqa: E402
from localizer_client import synth  # noqa: E402

SERVER = os.environ.get("LOCALIZER_SERVER", "")
FS_HZ = 44100.0
SOUND_SPEED_MPS = 1500.0
FRAME, HOP, BLOCK = 4096, 2048, 4096
BAND_HZ = (200.0, 8000.0)
SENSORS_M = synth.tetrahedron(edge_m=1.5)
SOURCE_M, TDOA_SAMPLES = synth.source_with_integer_tdoas(SENSORS_M, (2.5, 1.5, -1.0),
                                                         SOUND_SPEED_MPS, FS_HZ)
# 21 blocks of 4096 = 1.95 s; periodic, so any stretch of it is a valid recording.
AUDIO = synth.broadband_at_sensors(TDOA_SAMPLES, 21 * BLOCK, FS_HZ, band_hz=BAND_HZ,
                                   snr_db=20.0, seed=7)
# Position tolerance. The source is 3.2 m from the array centre, the array 1.5 m across: a
# TDOA error of half a sample on every pair moves the fix by about 0.2 m (mostly in range,
# computed with this geometry), and GCC-PHAT on these whole-sample delays at 20 dB SNR over
# 4096-sample frames errs by well under 0.1 sample. 0.5 m therefore allows more than a sample
# of error per pair, yet fails on wrong geometry, units, signs or pair order.
TOLERANCE_M = 0.5


def frames_completed(samples):
    """Frames (FRAME long, every HOP) that fit in the first `samples` samples."""
    return 0 if samples < FRAME else (samples - FRAME) // HOP + 1


def config(label):
    return lc.session_config(SENSORS_M, FS_HZ, sound_speed_mps=SOUND_SPEED_MPS,
                             frame_samples=FRAME, hop_samples=HOP, band_hz=BAND_HZ, seed=1,
                             label=label)


class SyntheticSignalTest(unittest.TestCase):
    """The recording matches the geometry (no server needed)."""

    def test_source_has_the_integer_tdoas(self):
        ranges = np.linalg.norm(SENSORS_M - SOURCE_M, axis=1)
        path_difference_m = ranges - ranges[0]
        np.testing.assert_allclose(path_difference_m, TDOA_SAMPLES * SOUND_SPEED_MPS / FS_HZ,
                                   atol=1e-9)
        self.assertEqual(list(TDOA_SAMPLES), [0, 6, 16, 38])
        self.assertLess(np.linalg.norm(SOURCE_M - np.array([2.5, 1.5, -1.0])), 0.3)

    def test_channels_carry_the_delays(self):
        # Whole-signal GCC-PHAT in numpy: the peak lag of channel k against channel 0 is the
        # arrival difference (positive: later at k).
        spectra = np.fft.rfft(AUDIO.astype(np.float64), axis=0)
        for k in range(1, 4):
            cross = spectra[:, k] * np.conj(spectra[:, 0])
            gcc = np.fft.irfft(cross / np.maximum(np.abs(cross), 1e-12), len(AUDIO))
            lag = int(np.argmax(gcc))
            lag = lag - len(AUDIO) if lag > len(AUDIO) // 2 else lag
            self.assertEqual(lag, TDOA_SAMPLES[k], f"sensor {k}")

    def test_a_proxy_reset_reads_as_unavailable(self):
        class Err(grpc.RpcError):
            def __init__(self, code, details):
                self._code, self._details = code, details

            def code(self):
                return self._code

            def details(self):
                return self._details

            def initial_metadata(self):
                return ()

            def trailing_metadata(self):
                return ()

        reset = Err(grpc.StatusCode.INTERNAL, "Received RST_STREAM with error code 2")
        lost = lc.from_proxy_reset(reset)
        self.assertIsInstance(lost, lc.InstanceLost)
        self.assertIsInstance(lost, grpc.RpcError)
        self.assertEqual(lost.code(), grpc.StatusCode.UNAVAILABLE)
        self.assertIn("RST_STREAM with error code 2", lost.details())
        self.assertIs(lost.cause, reset)
        for other in (Err(grpc.StatusCode.INTERNAL, "engine: non-finite covariance"),
                      Err(grpc.StatusCode.INTERNAL, "Received RST_STREAM with error code 8"),
                      Err(grpc.StatusCode.UNAVAILABLE, "server shutting down")):
            self.assertIs(lc.from_proxy_reset(other), other)

    def test_bounds_helper_sets_only_closed_sides(self):
        water = lc.bounds(surface_z_m=0.0, bottom_z_m=-8.0)
        self.assertTrue(water.HasField("max_z_m"))  # an explicit 0 is kept
        self.assertEqual((water.max_z_m, water.min_z_m), (0.0, -8.0))
        for field in ("min_x_m", "max_x_m", "min_y_m", "max_y_m"):
            self.assertFalse(water.HasField(field), field)
        box = lc.bounds((-10, None, float("-inf")), (10, float("inf"), 5))
        self.assertEqual((box.min_x_m, box.max_x_m, box.max_z_m), (-10.0, 10.0, 5.0))
        for field in ("min_y_m", "max_y_m", "min_z_m"):
            self.assertFalse(box.HasField(field), field)
        with self.assertRaises(ValueError):
            lc.bounds(max_m=(None, None, 1.0), surface_z_m=2.0)
        cfg = lc.session_config(SENSORS_M, FS_HZ, bounds=water, search_radius_m=40.0,
                                presence_false_alarm=0.01, source_timeout_s=3.0)
        self.assertEqual(cfg.bounds.min_z_m, -8.0)
        self.assertEqual((cfg.search_radius_m, cfg.presence_false_alarm, cfg.source_timeout_s),
                         (40.0, 0.01, 3.0))
        self.assertFalse(lc.session_config(SENSORS_M, FS_HZ).HasField("bounds"))

    def test_presence_summary_reports_a_run_with_no_source(self):
        silent = [lc.pb.Estimate(frame_index=k, presence_statistic=1.0 + 0.25 * k,
                                 presence_threshold=6.5) for k in range(12)]
        summary = lc.presence_summary(silent)
        self.assertTrue(summary["no_source"])
        self.assertEqual(summary["no_source_line"],
                         "no source found in 12 frames (presence statistic max 3.75, threshold 6.5)")
        heard = silent + [lc.pb.Estimate(frame_index=12, source_present=True, presence_statistic=9.0,
                                         presence_threshold=6.5, ambiguous=True, modes=2)]
        summary = lc.presence_summary(heard)
        self.assertFalse(summary["no_source"])
        self.assertEqual((summary["present"], summary["ambiguous"]), (1, 1))
        far = [lc.pb.Estimate(initialised=True, far_field=k % 2 == 0, range_sd_m=4.0) for k in range(5)]
        self.assertEqual((lc.presence_summary(far)["initialised"], lc.presence_summary(far)["far_field"]), (5, 3))
        # Estimates without a presence test (threshold 0: an older server) are not a silent run.
        self.assertFalse(lc.presence_summary([lc.pb.Estimate(initialised=True)])["no_source"])

    def test_loadtest_encodes_requests_like_protobuf(self):
        sys.path.insert(0, CLIENT_DIR)
        import loadtest
        args = loadtest.parse_args(["--target", "x:1", "--sessions", "2", "--duration", "1",
                                    "--rate", "max", "--signal-seconds", "0.2"])
        workload = loadtest.Workload(args)
        for seq in (1, 127, 128, 300000):
            raw = workload.block_request(seq, 1)
            expected = lc.pb.TrackRequest(block=lc.pb.SampleBlock.FromString(workload.bodies[1]))
            expected.block.sequence = seq
            self.assertEqual(lc.pb.TrackRequest.FromString(raw), expected)
        self.assertEqual(len(expected.block.samples), 4 * args.block)


class ServerFixture(unittest.TestCase):
    """A localizer-server on a loopback port per test, with a channel to it (no tests)."""

    def setUp(self):
        self.tmp = tempfile.mkdtemp(prefix="localizer-pytest-")
        ready = Path(self.tmp) / "ready.json"
        self.log = open(Path(self.tmp) / "server.log", "wb")
        self.server = subprocess.Popen(
            [SERVER, "--listen", "127.0.0.1:0", "--metrics-listen", "127.0.0.1:0",
             "--ready-file", str(ready), "--workers", "2"],
            stdout=self.log, stderr=subprocess.STDOUT)
        deadline = time.monotonic() + 30.0
        while not ready.exists():
            if self.server.poll() is not None:
                self.fail(f"server exited with {self.server.returncode}:\n{self.server_log()}")
            if time.monotonic() > deadline:
                self.fail(f"server wrote no ready file in 30 s:\n{self.server_log()}")
            time.sleep(0.05)
        info = json.loads(ready.read_text())
        self.target = f"127.0.0.1:{info['grpc_port']}"
        self.channel = lc.connect(self.target)
        grpc.channel_ready_future(self.channel).result(timeout=10)

    def tearDown(self):
        self.channel.close()
        self.server.send_signal(signal.SIGTERM)
        try:
            self.server.wait(timeout=20)
        except subprocess.TimeoutExpired:
            self.server.kill()
            self.server.wait()
            self.log.close()
            self.fail(f"server ignored SIGTERM for 20 s:\n{self.server_log()}")
        self.log.close()
        shutil.rmtree(self.tmp, ignore_errors=True)

    def server_log(self):
        self.log.flush()
        return (Path(self.tmp) / "server.log").read_bytes().decode(errors="replace")[-4000:]

    def stream(self, session, blocks, close=True):
        """Send `blocks` ((sequence, data) pairs) in real time from a thread."""
        def run():
            t0 = time.monotonic()
            for k, (sequence, data) in enumerate(blocks):
                time.sleep(max(0.0, k * BLOCK / FS_HZ - (time.monotonic() - t0)))
                session.send(data, sequence=sequence)
            if close:
                session.close()
        thread = threading.Thread(target=run, daemon=True)
        thread.start()
        return thread


@unittest.skipUnless(SERVER and os.access(SERVER, os.X_OK),
                     f"no localizer-server binary (LOCALIZER_SERVER={SERVER!r})")
class ServerTest(ServerFixture):
    def test_detection_session_confirms_two_targets(self):
        # Two targets 1 km apart moving at 20 m/s, noiseless plots every 2 s, plus a plot with a
        # negative range on the third scan (refused in-band, the session goes on).
        session = lc.TrackSession(self.channel, lc.detection_config(label="py-radar"), timeout=60)
        self.assertTrue(session.opened.effective_config.HasField("detections"))
        starts = np.array([[5000.0, 0.0], [5000.0, 1000.0]])
        velocity = np.array([0.0, 20.0])
        for k in range(6):
            t = 2.0 * k
            xy = starts + velocity * t
            ranges, bearings = np.hypot(xy[:, 0], xy[:, 1]), np.arctan2(xy[:, 1], xy[:, 0])
            if k == 2:
                session.send_scan(lc.scan(900, t, [-1.0], [0.0]))
            session.send_scan(lc.scan(k, t, ranges, bearings))
        session.close()
        lists = list(session.track_lists())
        self.assertEqual(session.code(), grpc.StatusCode.OK)
        self.assertEqual([tl.sequence for tl in lists], list(range(6)))
        self.assertEqual(len(session.rejected), 1)
        self.assertEqual(session.rejected[0].request, "scan")
        self.assertIn("range_m", session.rejected[0].message)
        last = lists[-1]
        confirmed = [t for t in last.tracks if t.status == lc.pb.TRACK_STATUS_CONFIRMED]
        self.assertEqual(sorted(t.id for t in confirmed), [1, 2])
        for track, start in zip(sorted(confirmed, key=lambda t: t.id), starts):
            want = start + velocity * 10.0
            self.assertLess(np.hypot(track.position_m.x - want[0], track.position_m.y - want[1]), 1.0)
            self.assertLess(abs(track.velocity_mps.y - 20.0), 1.0)

    def test_moving_array_session_reports_the_platform_pose(self):
        # The array at rest on a level platform: IMU reads gravity on +z and no rotation.
        platform = lc.platform_config(origin_m=(0.0, 0.0, 0.0))
        cfg = config("py-moving")
        cfg.platform.CopyFrom(platform)
        session = lc.TrackSession(self.channel, cfg, timeout=60)
        self.assertEqual(session.opened.effective_config.platform.attitude_filter, "quaternion")
        n_blocks = 6
        t_imu = np.arange(0.0, n_blocks * BLOCK / FS_HZ, 0.01)
        gyro = np.zeros((len(t_imu), 3))
        accel = np.tile([0.0, 0.0, 9.81], (len(t_imu), 1))
        session.send_imu(lc.imu_batch(1, t_imu, gyro, accel))
        bad = lc.imu_batch(2, [t_imu[-1] + 0.01], [[np.nan, 0.0, 0.0]], [[0.0, 0.0, 9.81]])
        session.send_imu(bad)
        for k in range(n_blocks):
            session.send(AUDIO[k * BLOCK:(k + 1) * BLOCK], sequence=k + 1)
        session.close()
        estimates = list(session.estimates())
        self.assertEqual(session.code(), grpc.StatusCode.OK)
        self.assertEqual(len(session.rejected), 1)
        self.assertEqual(session.rejected[0].request, "imu")
        self.assertIn("gyro_rps", session.rejected[0].message)
        self.assertEqual(len(estimates), frames_completed(n_blocks * BLOCK))
        for e in estimates:
            self.assertTrue(e.HasField("platform"))
            self.assertAlmostEqual(e.platform.body_to_world.w, 1.0, places=4)
            self.assertLess(abs(e.platform.euler_rad.x), 1e-3)

    def test_track_estimates_in_order_and_on_the_source(self):
        session = lc.TrackSession(self.channel, config("py-track"), timeout=60)
        self.assertTrue(session.session_id)
        self.assertTrue(session.resume_token)
        self.assertIn(session.opened.backend, ("cpu", "gpu"))
        self.assertEqual(session.opened.effective_config.frame_samples, FRAME)
        blocks = [(k + 1, AUDIO[k * BLOCK:(k + 1) * BLOCK]) for k in range(len(AUDIO) // BLOCK)]
        self.stream(session, blocks)
        estimates = list(session.estimates())
        self.assertEqual(session.code(), grpc.StatusCode.OK)
        self.assertEqual(session.rejected, [])
        self.assertEqual(session.gaps, [])

        n = frames_completed(len(AUDIO))  # 41: one estimate per completed frame
        self.assertEqual([e.frame_index for e in estimates], list(range(n)))
        # Each estimate names the block that completed its frame.
        self.assertEqual([e.sequence for e in estimates],
                         [-(-(FRAME + k * HOP) // BLOCK) for k in range(n)])
        self.assertEqual(session.last_frame_received, n - 1)
        last = estimates[-1]
        self.assertTrue(last.initialised)
        position = np.array([last.position_m.x, last.position_m.y, last.position_m.z])
        error_m = np.linalg.norm(position - SOURCE_M)
        self.assertLess(error_m, TOLERANCE_M,
                        f"final estimate {position} vs source {SOURCE_M}: {error_m:.3f} m")

    def test_bad_block_is_rejected_and_later_blocks_still_estimate(self):
        session = lc.TrackSession(self.channel, config("py-bad-block"), timeout=60)
        good = [AUDIO[k * BLOCK:(k + 1) * BLOCK] for k in range(len(AUDIO) // BLOCK)]
        bad = good[5][:, :3]  # 3 channels for a 4-sensor array
        blocks = ([(k + 1, good[k]) for k in range(5)] + [(6, bad)] +
                  [(k + 2, good[k]) for k in range(5, 15)])
        self.stream(session, blocks)
        estimates = list(session.estimates())
        self.assertEqual(session.code(), grpc.StatusCode.OK)

        self.assertEqual(len(session.rejected), 1, session.rejected)
        rejected = session.rejected[0]
        self.assertEqual(rejected.sequence, 6)
        self.assertEqual(rejected.code, "INVALID_ARGUMENT")
        self.assertEqual(rejected.reason, "channel_count")
        self.assertIn("channel_count", rejected.message)  # names the field ...
        self.assertIn("3", rejected.message)              # ... and the value
        # The session went on: frames stay numbered 0, 1, 2, ... and blocks after the bad one
        # complete frames. (Whether 5 -> 7 counts as a gap is the server's call.)
        self.assertEqual([e.frame_index for e in estimates], list(range(len(estimates))))
        self.assertTrue(any(e.sequence > 6 for e in estimates))
        self.assertGreaterEqual(len(estimates), frames_completed(15 * BLOCK) - 2)

    def test_list_sessions_shows_the_session(self):
        session = lc.TrackSession(self.channel, config("py-listed"), timeout=60)
        self.stream(session, [(k + 1, AUDIO[k * BLOCK:(k + 1) * BLOCK]) for k in range(3)],
                    close=False).join()
        responses = iter(session.estimates())
        next(responses)  # a frame has been processed
        infos = {s.session_id: s for s in lc.list_sessions(self.channel, timeout=10)}
        self.assertIn(session.session_id, infos)
        info = infos[session.session_id]
        self.assertEqual(info.label, "py-listed")
        self.assertTrue(info.attached)
        self.assertEqual(info.channel_count, 4)
        self.assertEqual(info.sample_rate_hz, FS_HZ)
        self.assertIn(info.backend, ("cpu", "gpu"))
        self.assertGreaterEqual(info.frames_processed, 1)
        session.close()
        list(responses)
        self.assertEqual(session.code(), grpc.StatusCode.OK)
        # A finished session is closed (proto: "ends the stream OK and closes the session").
        deadline = time.monotonic() + 5.0
        while session.session_id in {s.session_id for s in lc.list_sessions(self.channel)}:
            self.assertLess(time.monotonic(), deadline, "finished session still listed after 5 s")
            time.sleep(0.1)

    def test_bad_config_raises_invalid_argument(self):
        bad = config("py-bad-config")
        del bad.array.sensors_m[3]  # 3 sensors cannot give a 3-D fix
        bad.localization = "position"  # (they can give directions: "auto")
        with self.assertRaises(grpc.RpcError) as caught:
            lc.TrackSession(self.channel, bad, timeout=30)
        self.assertEqual(caught.exception.code(), grpc.StatusCode.INVALID_ARGUMENT)
        self.assertIn("sensors", caught.exception.details())

    def test_bounds_and_presence_config_echo_and_estimate_fields(self):
        cfg = config("py-bounds")
        cfg.bounds.CopyFrom(lc.bounds(surface_z_m=10.0, bottom_z_m=-20.0))
        cfg.presence_false_alarm = 0.01
        session = lc.TrackSession(self.channel, cfg, timeout=60)
        effective = session.opened.effective_config
        self.assertEqual((effective.bounds.max_z_m, effective.bounds.min_z_m), (10.0, -20.0))
        self.assertFalse(effective.bounds.HasField("min_x_m"))  # open sides stay unset
        self.assertEqual(effective.presence_false_alarm, 0.01)
        self.assertEqual(effective.source_timeout_s, 2.0)       # defaults are echoed
        self.assertEqual(effective.search_radius_m, 0.0)        # 0: 10 apertures
        for k in range(3):
            session.send(AUDIO[k * BLOCK:(k + 1) * BLOCK], sequence=k + 1)
        session.close()
        estimates = list(session.estimates())
        self.assertEqual(session.code(), grpc.StatusCode.OK)
        self.assertEqual(len(estimates), frames_completed(3 * BLOCK))
        for e in estimates:  # the fields exist with their types (values are the engine's)
            self.assertIsInstance(e.source_present, bool)
            self.assertIsInstance(e.ambiguous, bool)
            self.assertIsInstance(e.modes, int)
            self.assertGreaterEqual(e.presence_statistic, 0.0)

    def test_bad_bounds_raise_invalid_argument_naming_the_field(self):
        for bad, field in ((lc.bounds(surface_z_m=-5.0, bottom_z_m=0.0), "bounds.min_z_m"),
                           (lc.bounds(max_m=(float("nan"), None, None)), "bounds.max_x_m")):
            cfg = config("py-bad-bounds")
            cfg.bounds.CopyFrom(bad)
            with self.assertRaises(grpc.RpcError) as caught:
                lc.TrackSession(self.channel, cfg, timeout=30)
            self.assertEqual(caught.exception.code(), grpc.StatusCode.INVALID_ARGUMENT)
            self.assertIn(field, caught.exception.details())
        cfg = config("py-bad-presence")
        cfg.presence_false_alarm = 0.5
        with self.assertRaises(grpc.RpcError) as caught:
            lc.TrackSession(self.channel, cfg, timeout=30)
        self.assertEqual(caught.exception.code(), grpc.StatusCode.INVALID_ARGUMENT)
        self.assertIn("presence_false_alarm", caught.exception.details())

    def test_close_session_needs_the_token_and_cancels_the_stream(self):
        session = lc.TrackSession(self.channel, config("py-close"), timeout=60)
        with self.assertRaises(grpc.RpcError) as caught:
            lc.close_session(self.channel, session.session_id, "wrong-token", timeout=10)
        self.assertEqual(caught.exception.code(), grpc.StatusCode.PERMISSION_DENIED)
        lc.close_session(self.channel, session.session_id, session.resume_token, timeout=10)
        with self.assertRaises(grpc.RpcError) as caught:
            list(session)
        self.assertEqual(caught.exception.code(), grpc.StatusCode.CANCELLED)
        with self.assertRaises(grpc.RpcError) as caught:
            lc.close_session(self.channel, session.session_id, session.resume_token, timeout=10)
        self.assertEqual(caught.exception.code(), grpc.StatusCode.NOT_FOUND)

    def test_locate_one_block(self):
        response = lc.locate(self.channel, config("py-locate"), AUDIO[:2 * BLOCK], timeout=30)
        self.assertEqual([p.sensor for p in response.pairs], [1, 2, 3])
        for pair in response.pairs:  # whole-sample delays: measured within half a sample
            self.assertAlmostEqual(pair.delay_s * FS_HZ, TDOA_SAMPLES[pair.sensor], delta=0.5)
        self.assertTrue(response.fix_found)
        position = np.array([response.position_m.x, response.position_m.y, response.position_m.z])
        self.assertLess(np.linalg.norm(position - SOURCE_M), TOLERANCE_M)

    def test_reflection_lists_the_service_and_health_is_serving(self):
        # Hand-encoded messages: Debian packages neither grpcio-reflection nor grpcio-health.
        # ServerReflectionRequest{list_services: ""} is field 7, length 0.
        reflect = self.channel.stream_stream(
            "/grpc.reflection.v1alpha.ServerReflection/ServerReflectionInfo",
            request_serializer=None, response_deserializer=None)
        replies = list(reflect(iter([b"\x3a\x00"]), timeout=10))
        self.assertEqual(len(replies), 1)
        self.assertIn(b"localizer.v1.Localizer", replies[0])
        self.assertIn(b"grpc.health.v1.Health", replies[0])
        # HealthCheckRequest{} -> HealthCheckResponse{status: SERVING (1)}.
        check = self.channel.unary_unary("/grpc.health.v1.Health/Check",
                                         request_serializer=None, response_deserializer=None)
        self.assertEqual(check(b"", timeout=10), b"\x08\x01")

    def test_loadtest_realtime_4_sessions(self):
        run = subprocess.run(
            [sys.executable, str(Path(CLIENT_DIR) / "loadtest.py"), "--target", self.target,
             "--sessions", "4", "--duration", "3", "--rate", "realtime"],
            capture_output=True, text=True, timeout=120)
        self.assertEqual(run.returncode, 0, f"stdout:\n{run.stdout}\nstderr:\n{run.stderr}")
        lines = [line for line in run.stdout.splitlines() if line.startswith("RESULT ")]
        self.assertEqual(len(lines), 1, run.stdout)
        result = json.loads(lines[0][len("RESULT "):])
        self.assertEqual(result["errors"], {})
        self.assertEqual(result["rejections"], {})
        self.assertEqual(result["sessions_opened"], 4)
        blocks_per_session = -(-3.0 * 44100 // 4096)  # one per 4096/44100 s for 3 s: 33
        self.assertEqual(result["blocks_sent"], 4 * blocks_per_session)
        self.assertGreater(result["estimates"], 0)
        self.assertIsNotNone(result["latency_ms"]["p99"])


if __name__ == "__main__":
    unittest.main(verbosity=2)
