"""localizer.engine, the engine's in-process bindings, against physics and against the CLI.

- GCC-PHAT of a pair gives the delay the geometry gives (a band-limited noise delayed by a
  fractional number of samples in the frequency domain), with the engine's sign convention;
  the array form gives every pair's model TDOA.
- Multilateration of exact model TDOAs returns the true position.
- A simulated scene processed through Session gives exactly (every bit of every field the
  CLI writes) the estimates `localizer-cli track --format jsonl` writes for the same WAV and
  array.json with the same filter seed; the binding's simulator renders that WAV's samples.
- A bad block raises ValueError and leaves the session as it was: the stream then gives the
  same estimates as one that never saw the bad block.
- The engine runs without the GIL: the main thread keeps running Python while another
  thread's Session.process computes, and sessions in two threads give what they give alone.
- The attitude filter finds a static tilt from gravity; the TWS tracker confirms two targets.
- The stub's Session defaults are the ones the module applies.
Every random draw is seeded. Skips the CLI comparison (with the reason) without localizer-cli.
"""
import ast
import json
import math
import os
import subprocess
import sys
import tempfile
import threading
import time
import unittest
from pathlib import Path

CLIENT_DIR = os.environ.get("LOCALIZER_PY_CLIENT_DIR") or str(
    Path(__file__).resolve().parents[2] / "build" / "clients" / "python")
sys.path.insert(0, CLIENT_DIR)

import numpy as np  # noqa: E402

import localizer.audio  # noqa: E402
import localizer.engine as le  # noqa: E402

CLI = os.environ.get("LOCALIZER_CLI", "")
STUB = Path(__file__).resolve().parents[2] / "clients" / "python" / "localizer" / "engine.pyi"
TETRA_M = np.array([[0.0, 0.0, 0.0], [2.0, 0.0, 0.0], [0.0, 2.0, 0.0], [0.0, 0.0, 2.0]])


def delayed_noise(delays_s, fs, n, band_hz=(200.0, 4000.0), seed=7):
    """(n, channels) float64: one band-limited white noise, channel k delayed by delays_s[k]
    (fractional delays applied exactly as phase shifts; the frame is cut from the middle of a
    4x longer record so that the circular shift does not wrap into it)."""
    rng = np.random.default_rng(seed)
    total = 4 * n
    spectrum = np.fft.rfft(rng.standard_normal(total))
    f = np.fft.rfftfreq(total, 1.0 / fs)
    spectrum[(f < band_hz[0]) | (f > band_hz[1])] = 0.0
    start = (total - n) // 2
    channels = [np.fft.irfft(spectrum * np.exp(-2j * np.pi * f * d), total)[start:start + n] for d in delays_s]
    return np.stack(channels, axis=1)


class PairGccTest(unittest.TestCase):
    def test_known_geometry_gives_the_known_delay(self):
        fs, c = 11025.0, 1500.0
        m0, m1 = np.zeros(3), np.array([1.5, 0.0, 0.0])
        source = 20.0 * np.array([math.cos(math.radians(60)), math.sin(math.radians(60)), 0.0])
        # t_arrival(m1) - t_arrival(m0): positive when the source is nearer m0.
        delay_s = (np.linalg.norm(source - m1) - np.linalg.norm(source - m0)) / c
        x = delayed_noise([0.0, delay_s], fs, 4096)
        # The source's band given, as gcc_phat.h asks: PHAT would otherwise whiten the float32
        # rounding noise of the empty bins to the signal's weight (a few tenths of a sample off).
        band = dict(band_low_hz=200.0, band_high_hz=4000.0)
        result = le.gcc_phat_pair(x[:, 0], x[:, 1], fs, max_delay_s=1.5 / c, **band)
        self.assertLess(abs(result["delay_s"] - delay_s) * fs, 0.01, result)  # samples
        self.assertAlmostEqual(result["delay_samples"], result["delay_s"] * fs)
        self.assertGreater(result["peak_value"], 0.5)  # read at the integer lag (gcc_phat.h)
        self.assertGreater(result["quality"], 2.0)
        self.assertLess(result["delay_sigma_s"] * fs, 0.05)
        swapped = le.gcc_phat_pair(x[:, 1], x[:, 0], fs, max_delay_s=1.5 / c, **band)
        self.assertLess(abs(swapped["delay_s"] + delay_s) * fs, 0.01)

    def test_bad_pairs_raise_value_error(self):
        x = np.zeros(4096)
        for args in ((x, x[:100], 8000.0, 1e-3), (x, x, 8000.0, 0.0), (x, x, 8000.0, float("nan")),
                     (x.reshape(64, 64), x.reshape(64, 64), 8000.0, 1e-3), (x[:0], x[:0], 8000.0, 1e-3),
                     (x, x, -1.0, 1e-3)):
            with self.assertRaises(ValueError):
                le.gcc_phat_pair(*args)
        with self.assertRaises(ValueError):  # a non-finite sample: the engine's INVALID_ARGUMENT
            le.gcc_phat_pair(np.full(4096, np.nan), x, 8000.0, 1e-3)

    def test_array_frame_gives_every_pairs_model_tdoa(self):
        fs, c = 11025.0, 1500.0
        source = np.array([12.0, -7.0, 4.0])
        arrival_s = np.linalg.norm(source - TETRA_M, axis=1) / c
        frame = delayed_noise(arrival_s - arrival_s[0], fs, 4096).astype(np.float32)
        band = dict(band_low_hz=200.0, band_high_hz=4000.0)
        pairs = le.gcc_phat(frame, TETRA_M, fs, sound_speed_mps=c, **band)
        model = le.model_tdoa(TETRA_M, source, sound_speed_mps=c)
        self.assertEqual(list(pairs["sensor"]), [1, 2, 3])
        np.testing.assert_allclose(pairs["delay_s"], model, atol=0.01 / fs)
        # Interleaved (C order) and channel-major (F order) blocks are the same frame.
        again = le.gcc_phat(np.ascontiguousarray(frame), TETRA_M, fs, sound_speed_mps=c, **band)
        np.testing.assert_array_equal(again["delay_s"], pairs["delay_s"])
        with self.assertRaises(ValueError):  # 3 channels for 4 sensors
            le.gcc_phat(frame[:, :3], TETRA_M, fs)
        with self.assertRaises(ValueError):  # a planar array cannot localise in 3-D
            le.gcc_phat(frame, TETRA_M * [1, 1, 0], fs)


class MultilaterationTest(unittest.TestCase):
    def test_exact_tdoas_give_the_true_position(self):
        sensors = np.array([[0, 0, 0], [3, 0, 0], [0, 3, 0], [0, 0, 3], [2, 2, 2]], dtype=float)
        for source in ([10.0, 4.0, -3.0], [-6.0, 8.0, 5.0], [1.0, 1.5, 1.2]):
            fix = le.multilaterate(sensors, le.model_tdoa(sensors, source), sound_speed_mps=1500.0)
            np.testing.assert_allclose(fix["position_m"], source, atol=1e-6)
            self.assertLess(fix["rms_residual_s"], 1e-12)
            self.assertTrue(fix["converged"])
            self.assertEqual(fix["covariance_m2"].shape, (3, 3))

    def test_wrong_tdoa_count_raises_value_error(self):
        with self.assertRaises(ValueError):
            le.multilaterate(TETRA_M, [1e-4, 2e-4])
        with self.assertRaises(ValueError):
            le.multilaterate(TETRA_M, [1e-4, float("nan"), 0.0])


def jsonl_rows(path):
    return [json.loads(line) for line in Path(path).read_text().splitlines() if line.strip()]


def same_number(a, b):
    """JSON's null is the CLI's NaN (JSON has none)."""
    if a is None:
        return b is None or math.isnan(b)
    return a == b


@unittest.skipUnless(CLI and os.access(CLI, os.X_OK), "localizer-cli not built (LOCALIZER_CLI unset)")
class SessionMatchesCliTest(unittest.TestCase):
    SEED_SCENE, SEED_FILTER, DURATION_S = 3, 5, 6.0

    @classmethod
    def setUpClass(cls):
        cls.tmp = Path(tempfile.mkdtemp(prefix="localizer-engine-test-"))
        subprocess.run([CLI, "simulate", "--scenario", "tetra-water", "--seed", str(cls.SEED_SCENE),
                        "--duration", str(cls.DURATION_S), "--out", str(cls.tmp)],
                       check=True, capture_output=True, timeout=300)
        subprocess.run([CLI, "track", "--wav", str(cls.tmp / "signals.wav"), "--array",
                        str(cls.tmp / "array.json"), "--filter-seed", str(cls.SEED_FILTER), "--format", "jsonl",
                        "--out", str(cls.tmp / "estimates.jsonl"), "--print-every", "0"],
                       check=True, capture_output=True, timeout=300)
        cls.cli = jsonl_rows(cls.tmp / "estimates.jsonl")
        cls.array = json.loads((cls.tmp / "array.json").read_text())

    def session(self, fs):
        a = self.array
        band = a.get("band_hz")
        # As the CLI applies the array file's band hint (clients/io/track_runner.cc).
        return le.Session(np.array(a["sensors_m"], dtype=float), fs, sound_speed_mps=a["sound_speed_mps"],
                          reference_sensor=a.get("reference_sensor", 0), band_low_hz=band[0],
                          band_high_hz=min(band[1], fs / 2), seed=self.SEED_FILTER)

    def test_simulator_binding_renders_the_clis_wav(self):
        samples, fs = localizer.audio.read(str(self.tmp / "signals.wav"))
        scene = le.simulate_scenario("tetra-water", self.SEED_SCENE, duration_s=self.DURATION_S)
        self.assertEqual(scene["sample_rate_hz"], fs)
        np.testing.assert_array_equal(scene["samples"], samples.T)
        np.testing.assert_array_equal(scene["sensors_m"], np.array(self.array["sensors_m"]))

    def test_session_gives_exactly_the_clis_estimates(self):
        samples, fs = localizer.audio.read(str(self.tmp / "signals.wav"))  # (channels, samples)
        session = self.session(fs)
        block = int(0.1 * fs)  # any block size: the session frames by hop, not by block
        frames = np.concatenate([session.process(samples.T[i:i + block]) for i in range(0, samples.shape[1], block)])
        self.assertEqual(len(frames), len(self.cli))
        self.assertGreater(int(frames["initialised"].sum()), len(frames) // 2, "the scene was not tracked")
        for row, e in zip(frames, self.cli):
            self.assertEqual(row["frame_index"], e["frame"])
            self.assertEqual(row["t_s"], e["t_s"])
            for name in ("initialised", "reinitialised", "source_present", "ambiguous", "far_field"):
                self.assertEqual(bool(row[name]), e[name], name)
            for name in ("modes", "pairs_used"):
                self.assertEqual(int(row[name]), e[name], name)
            for name in ("presence_statistic", "presence_threshold", "range_sd_m", "nis", "ess", "tdoa_sigma_s"):
                self.assertTrue(same_number(e[name], float(row[name])), (name, e[name], row[name]))
            for p, pair in enumerate(e["pairs"]):
                self.assertTrue(same_number(pair["delay_s"], float(row["delay_s"][p])), pair)
                self.assertTrue(same_number(pair["quality"], float(row["quality"][p])), pair)
            if e["initialised"]:
                self.assertEqual(list(row[["x_m", "y_m", "z_m"]].item()), e["position_m"])
                self.assertEqual(list(row[["vx_mps", "vy_mps", "vz_mps"]].item()), e["velocity_mps"])
                self.assertEqual(row["covariance"].tolist(), e["covariance"])

    def test_resolved_config_is_the_clis(self):
        samples, fs = localizer.audio.read(str(self.tmp / "signals.wav"))
        config = self.session(fs).config
        self.assertEqual(config["localization"], "position")
        self.assertEqual((config["frame_samples"], config["hop_samples"]), (4096, 2048))
        self.assertEqual(config["seed"], self.SEED_FILTER)
        self.assertEqual(config["filter"], "pf")


def without_wall_times(frames):
    """Every field but the stage wall times, which differ run to run."""
    return frames[[n for n in frames.dtype.names if not n.endswith("_wall_s")]]


class SessionContractTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.scene = le.simulate_scenario("tetra-water", seed=2, duration_s=4.0)

    def session(self, seed=4, particles=1024):
        s = self.scene
        return le.Session(s["sensors_m"], s["sample_rate_hz"], sound_speed_mps=s["sound_speed_mps"],
                          band_low_hz=s["band_hz"][0], band_high_hz=s["band_hz"][1], seed=seed,
                          particles=particles)

    def test_bad_blocks_raise_value_error_and_the_session_keeps_working(self):
        x = self.scene["samples"]
        half = len(x) // 2
        reference = self.session()
        expected = np.concatenate([reference.process(x[:half]), reference.process(x[half:])])
        session = self.session()
        first = session.process(x[:half])
        nan_block = x[half:half + 1000].copy()
        nan_block[10, 2] = np.nan
        for bad in (x[half:half + 1000, :3],             # 3 channels for 4 sensors
                    nan_block,                           # a non-finite sample
                    x[:0],                               # empty
                    x[half:half + 1000, 0],              # 1-D
                    x[half:half + 1000].astype(np.int16),  # not floating point
                    x[half:half + 1000].astype(np.complex64)):
            with self.assertRaises(ValueError):
                session.process(bad)
        rest = session.process(x[half:])
        np.testing.assert_array_equal(without_wall_times(np.concatenate([first, rest])),
                                      without_wall_times(expected))
        with self.assertRaises(ValueError):
            session.skip(-1)

    def test_float64_and_interleaved_blocks_give_the_same_estimates(self):
        x = self.scene["samples"]  # F order float32: used in place
        a = self.session().process(x)
        b = self.session().process(np.ascontiguousarray(x, dtype=np.float64))
        np.testing.assert_array_equal(a[["t_s", "x_m", "y_m", "z_m"]], b[["t_s", "x_m", "y_m", "z_m"]])

    def test_bad_configs_raise(self):
        s = self.scene
        with self.assertRaises(ValueError):
            le.Session(s["sensors_m"][:, :2], s["sample_rate_hz"])   # (N, 2) positions
        with self.assertRaises(ValueError):
            le.Session(s["sensors_m"], -1.0)                         # engine: sample rate
        with self.assertRaises(ValueError):
            le.Session(s["sensors_m"], s["sample_rate_hz"], filter="kalman")  # engine: unknown name
        with self.assertRaises(TypeError):
            le.Session(s["sensors_m"], s["sample_rate_hz"], frame_sampels=1024)
        with self.assertRaises(RuntimeError):  # no GPU backend in the bindings: FAILED_PRECONDITION
            le.Session(s["sensors_m"], s["sample_rate_hz"], backend="gpu")

    def test_the_engine_runs_without_the_gil(self):
        # 144 s of audio: a few tenths of a second of work even on a quiet, fast host (48 s took
        # 0.06 s on one, under the 0.1 s this test needs to tell a held GIL from a released one)
        x = np.concatenate([self.scene["samples"]] * 36)
        alone = [self.session(seed=k, particles=4096).process(x) for k in (1, 2)]
        results, inside, spans = {}, threading.Event(), {}

        def run(k):
            session = self.session(seed=k, particles=4096)
            inside.set()
            t0 = time.perf_counter()
            results[k] = session.process(x)
            spans[k] = time.perf_counter() - t0

        threads = [threading.Thread(target=run, args=(k,)) for k in (1, 2)]
        for t in threads:
            t.start()
        inside.wait()
        last, longest_gap_s = time.perf_counter(), 0.0
        while any(t.is_alive() for t in threads):  # runs only while no thread holds the GIL
            now = time.perf_counter()
            longest_gap_s, last = max(longest_gap_s, now - last), now
        for t in threads:
            t.join()
        # Held through process(), the GIL would stop this loop for a whole call; released, the
        # loop only waits for its turn on a CPU (a switch interval, 5 ms, or a scheduler slice).
        self.assertGreater(min(spans.values()), 0.1, f"too little work to tell: {spans}")
        self.assertLess(longest_gap_s, 0.5 * min(spans.values()), (longest_gap_s, spans))
        for k, expected in zip((1, 2), alone):
            np.testing.assert_array_equal(without_wall_times(results[k]), without_wall_times(expected))

    def test_stub_defaults_are_the_modules(self):
        tree = ast.parse(STUB.read_text())
        session = next(n for n in tree.body if isinstance(n, ast.ClassDef) and n.name == "Session")
        init = next(n for n in session.body if isinstance(n, ast.FunctionDef) and n.name == "__init__")
        stub = {a.arg: ast.literal_eval(d) for a, d in zip(init.args.kwonlyargs, init.args.kw_defaults)}
        module = le.Session.default_options()
        self.assertEqual(set(stub), set(module))
        for name, value in stub.items():
            if value is None:  # None: the engine's default vector (or a resolved framing)
                continue
            self.assertEqual(module[name], value, name)


class AttitudeAndTwsTest(unittest.TestCase):
    def test_static_tilt_is_found_from_gravity(self):
        g, roll = 9.81, math.radians(10.0)
        n = 400  # 4 s at 100 Hz
        t = np.arange(n) * 0.01
        accel = np.tile([0.0, g * math.sin(roll), g * math.cos(roll)], (n, 1))
        out = le.AttitudeFilter("quaternion").update(t, np.zeros((n, 3)), accel)
        self.assertEqual(len(out), n)
        self.assertTrue(out["initialised"][-1])
        self.assertAlmostEqual(abs(out["euler_rad"][-1, 0]), roll, delta=math.radians(0.5))
        self.assertAlmostEqual(out["euler_rad"][-1, 1], 0.0, delta=math.radians(0.5))
        np.testing.assert_allclose(np.linalg.norm(out["quaternion"], axis=1), 1.0, atol=1e-9)
        bad_t = t.copy()
        bad_t[5] = bad_t[4]  # not increasing
        with self.assertRaises(ValueError):
            le.AttitudeFilter().update(bad_t, np.zeros((n, 3)), accel)

    def test_tws_confirms_two_targets_with_stable_ids(self):
        tracker = le.TwsTracker(dimensions=3)
        rng = np.random.default_rng(11)
        start = np.array([[0.0, 0.0, 0.0], [1000.0, 500.0, 0.0]])
        velocity = np.array([[50.0, 10.0, 0.0], [-40.0, 20.0, 0.0]])
        ids = None
        for scan in range(12):
            time_s = 2.0 * scan
            truth = start + velocity * time_s
            plots = truth + rng.normal(0.0, 5.0, truth.shape)
            tracker.process_cartesian(time_s, plots, np.tile(np.eye(3) * 25.0, (2, 1, 1)))
            confirmed = tracker.tracks(include_tentative=False)
            if len(confirmed) == 2:
                order = np.argsort(confirmed["position_m"][:, 1])  # target 2 stays north of 1
                ids = ids if ids is not None else confirmed["id"][order].tolist()
                self.assertEqual(confirmed["id"][order].tolist(), ids)
        self.assertIsNotNone(ids, "no scan had two confirmed tracks")
        final = tracker.tracks(include_tentative=False)
        for track in final:
            error = np.min(np.linalg.norm(truth - track["position_m"], axis=1))
            self.assertLess(error, 25.0)


if __name__ == "__main__":
    unittest.main(verbosity=2)
