"""localizer.session_file, the array file's "session" object read in Python, against
localizer-cli and localizer.engine (issue 19: one session file for every reader).

- The reader takes the array and its settings; an array file without "session" reads as before.
- It refuses what localizer-cli refuses, as a ValueError naming the file and the key: unknown,
  misplaced and engine-only keys, wrong JSON types, unknown names, the engine's ranges; the
  same files run through `localizer-cli track` are refused by it too (and the edge cases both
  accept, both accept).
- Its keys are localizer.engine.Session's option names and its names the ones the engine takes.
- ``engine_options`` open in localizer.engine the session `localizer-cli track --format jsonl`
  runs with the same file: every field the CLI writes equal, frame for frame.
- ``to_session_config`` sets the pb.SessionConfig fields the file states, and refuses what
  the wire cannot carry; on a localizer-server the session it opens streams the estimates
  `localizer-cli track` writes locally with the same file, frame for frame.
Skips the CLI comparisons without localizer-cli, the engine one without localizer.engine, the
server one without localizer-server (each with the reason).
"""
import json
import math
import os
import subprocess
import sys
import tempfile
import unittest
from pathlib import Path

CLIENT_DIR = os.environ.get("LOCALIZER_PY_CLIENT_DIR") or str(
    Path(__file__).resolve().parents[2] / "build" / "clients" / "python")
sys.path.insert(0, CLIENT_DIR)

import grpc  # noqa: E402
import numpy as np  # noqa: E402

import localizer  # noqa: E402
from localizer import pb  # noqa: E402
from localizer.session_file import CHOICES, SESSION_KEYS, parse_session_file, read_session_file  # noqa: E402

try:
    import localizer.engine as le
except ImportError as e:  # built without pybind11
    le, LE_MISSING = None, str(e)
else:
    LE_MISSING = ""

CLI = os.environ.get("LOCALIZER_CLI", "")
HAVE_CLI = bool(CLI) and os.access(CLI, os.X_OK)
TETRA = {"sound_speed_mps": 1500, "sensors_m": [[0, 0, 0], [2, 0, 0], [0, 2, 0], [0, 0, 2]]}


def text(session=None, **top):
    root = dict(TETRA, **top)
    if session is not None:
        root["session"] = session
    return json.dumps(root)


# Session objects both readers refuse, and the key each message must name.
BAD = [
    ({"partcles": 1024}, 'unknown key "partcles"'),
    ({"sound_speed_mps": 343}, "session.sound_speed_mps"),
    ({"source_plane_normal": [0, 0, 1]}, "session.source_plane_normal"),
    ({"divergence_window": 4}, "session.divergence_window"),
    ({"particles": "many"}, "session.particles"),
    ({"particles": 1024.5}, "session.particles"),
    ({"frame_samples": True}, "session.frame_samples"),
    ({"seed": -1}, "session.seed"),
    ({"accel_noise_mps2": "1"}, "session.accel_noise_mps2"),
    ({"filter": "kalman"}, "session.filter"),
    ({"imm_modes": "cv,cv"}, "session.imm_modes"),
    ({"weighting": "gcc"}, "session.weighting"),
    ({"backend": "tpu"}, "session.backend"),
    ({"particles": 8}, "particles"),
    ({"hop_samples": 8192}, "hop_samples"),
    ({"motion_model": "ct"}, "motion_model"),
    ({"presence_false_alarm": 0.5}, "presence_false_alarm"),
    ({"band_low_hz": 3000, "band_high_hz": 300}, "band_high_hz"),
    ({"despike_k": 0.5}, "despike_k"),
    ({"accel_level_floor": 4}, "accel_level_floor"),
    ({"manoeuvre_share": 1}, "manoeuvre_share"),
    ({"direction_diffuse_weighting": 1}, "session.direction_diffuse_weighting"),
    ({"direction_signal_weighting": "on"}, "session.direction_signal_weighting"),
    ({"direction_present_hold_s": 2}, "direction_present_hold_s"),
]
# Edge cases both accept.
GOOD = [
    {},
    {"hop_samples": 8192, "frame_samples": 16384},
    {"motion_model": "ct", "filter": "ukf"},
    {"accel_level_floor": 0.01, "accel_level_ceiling": 3, "despike_k": 0, "tdoa_sigma_s": 0},
    {"seed": 2**64 - 1, "band_high_hz": 20000},
    {"direction_present_hold_s": 0, "direction_diffuse_weighting": False, "direction_signal_weighting": True},
]


class ReaderTest(unittest.TestCase):
    def test_reads_the_array_and_its_settings(self):
        sf = parse_session_file(text({"particles": 1024, "filter": "ekf", "imm_modes": "ca,cv"}, sample_rate_hz=11025,
                                     reference_sensor=1, band_hz=[300, 3000], surface_z_m=7.0,
                                     localization="position"), "dir/a.json")
        np.testing.assert_array_equal(sf.sensors_m, np.array(TETRA["sensors_m"], float))
        self.assertEqual((sf.sound_speed_mps, sf.sample_rate_hz, sf.reference_sensor), (1500.0, 11025.0, 1))
        self.assertEqual(sf.session, {"particles": 1024, "filter": "ekf", "imm_modes": "ca,cv"})
        self.assertEqual(sf.bounds_max_m, (math.inf, math.inf, 7.0))
        self.assertEqual(sf.options, {
            "sound_speed_mps": 1500.0, "reference_sensor": 1, "localization": "position", "particles": 1024,
            "filter": "ekf", "imm_modes": "ca,cv", "band_low_hz": 300.0, "band_high_hz": 3000.0,
            "bounds_min_m": (-math.inf,) * 3, "bounds_max_m": (math.inf, math.inf, 7.0)})
        self.assertEqual(len(SESSION_KEYS), 32)

    def test_an_array_file_without_session_reads_as_before(self):
        sf = parse_session_file(text())
        self.assertEqual(sf.session, {})
        self.assertEqual(sf.options, {"sound_speed_mps": 1500.0, "reference_sensor": 0, "localization": "auto"})

    def test_the_band_hint_is_capped_at_nyquist_and_a_session_band_replaces_it(self):
        sf = parse_session_file(text(band_hz=[300, 8000]))
        self.assertEqual(sf.engine_options(11025.0)["band_high_hz"], 5512.5)
        sf = parse_session_file(text({"band_low_hz": 500}, band_hz=[300, 8000]))
        self.assertEqual((sf.options["band_low_hz"], sf.options["band_high_hz"]), (500.0, 0.0))

    def test_refusals_are_value_errors_naming_the_file_and_the_key(self):
        for session, key in BAD:
            with self.subTest(session=session):
                with self.assertRaises(ValueError) as caught:
                    parse_session_file(text(session), "dir/a.json")
                self.assertIn("dir/a.json: session", str(caught.exception))
                self.assertIn(key, str(caught.exception))
        for session in GOOD:
            parse_session_file(text(session), "dir/a.json")

    def test_top_level_errors_name_the_field(self):
        for top, field in (({"sesion": {}}, '"sesion"'), ({"session": [1]}, "session is [1]"),
                           ({"bounds_min_m": [0, 0, "x"]}, "bounds_min_m[2]"), ({"max_sources": 17}, "max_sources")):
            with self.subTest(top=top):
                with self.assertRaises(ValueError) as caught:
                    parse_session_file(text(**top), "dir/a.json")
                self.assertIn("dir/a.json: ", str(caught.exception))
                self.assertIn(field, str(caught.exception))

    def test_read_session_file_names_the_path(self):
        with tempfile.TemporaryDirectory() as tmp:
            path = Path(tmp) / "array.json"
            path.write_text(text({"partcles": 1}))
            with self.assertRaisesRegex(ValueError, f"{path}: session: unknown key"):
                read_session_file(path)
        self.assertIs(localizer.read_session_file, read_session_file)


class SessionConfigTest(unittest.TestCase):
    def test_the_file_sets_the_fields_it_states(self):
        sf = parse_session_file(text(
            {"frame_samples": 2048, "hop_samples": 512, "weighting": "phat-beta", "phat_beta": 0.6, "despike_k": 4,
             "filter": "imm", "imm_modes": "ca,cv", "imm_variant": "ukf", "robust": "huber", "particles": 1024,
             "likelihood": "mixture", "outlier_probability": 0.1, "tdoa_sigma_s": 2.5e-05, "accel_noise_mps2": 0.5,
             "manoeuvre_share": 0.0, "manoeuvre_scale": 5, "accel_level_floor": 0.01, "accel_level_ceiling": 3,
             "accel_level_switch_hz": 0, "turn_rate_max_radps": 0.8, "speed_change_max_mps2": 1.5, "seed": 42, "search_radius_m": 30, "presence_false_alarm": 0.01,
             "source_timeout_s": 3, "backend": "auto", "direction_present_hold_s": 0.0,
             "direction_diffuse_weighting": False, "direction_signal_weighting": True},
            sample_rate_hz=11025, reference_sensor=2, band_hz=[300, 8000], bottom_z_m=-5.0, max_sources=3,
            source_side={"normal": [0, 0, 1]}))
        c = sf.to_session_config(label="tank")
        self.assertEqual(len(c.array.sensors_m), 4)
        self.assertEqual((c.array.sensors_m[1].x, c.array.sound_speed_mps, c.array.reference_sensor), (2.0, 1500.0, 2))
        self.assertEqual((c.sample_rate_hz, c.label, c.localization), (11025.0, "tank", "auto"))
        self.assertEqual((c.band_low_hz, c.band_high_hz), (300.0, 5512.5))  # the hint, capped at Nyquist
        self.assertEqual((c.frame_samples, c.hop_samples, c.weighting, c.phat_beta, c.despike_k),
                         (2048, 512, pb.WEIGHTING_PHAT_BETA, 0.6, 4.0))
        f = c.filter
        self.assertEqual((f.type, f.imm_modes, f.imm_variant, f.robust, f.particles, f.likelihood),
                         (pb.FILTER_TYPE_IMM, "ca,cv", "ukf", "huber", 1024, pb.LIKELIHOOD_MIXTURE))
        self.assertEqual((f.outlier_probability, f.tdoa_sigma_s, f.accel_noise_mps2, f.manoeuvre_scale),
                         (0.1, 2.5e-05, 0.5, 5.0))
        self.assertTrue(f.HasField("manoeuvre_share"))  # 0 stated: optional on the wire, so it is carried
        self.assertEqual((f.accel_level_floor, f.accel_level_ceiling, f.accel_level_switch_hz), (0.01, 3.0, -1.0))
        self.assertEqual(f.turn_rate_max_radps, 0.8)
        self.assertEqual(f.speed_change_max_mps2, 1.5)
        self.assertEqual(f.motion_model, "")  # not stated: the server's default
        self.assertTrue(c.HasField("seed"))
        self.assertEqual((c.seed, c.search_radius_m, c.presence_false_alarm, c.source_timeout_s, c.backend),
                         (42, 30.0, 0.01, 3.0, "auto"))
        self.assertEqual((c.bounds.min_z_m, c.bounds.HasField("max_z_m"), c.bounds.HasField("min_x_m")),
                         (-5.0, False, False))
        self.assertEqual((c.max_sources, c.source_side.z), (3, 1.0))
        self.assertTrue(c.HasField("direction_present_hold_s"))  # 0 stated: optional, so carried
        self.assertEqual((c.direction_present_hold_s, c.direction_diffuse_weighting, c.direction_signal_weighting),
                         (0.0, False, True))

    def test_unstated_fields_are_left_to_the_server(self):
        c = parse_session_file(text()).to_session_config(16000.0)
        self.assertEqual((c.frame_samples, c.filter.particles, c.backend, c.band_high_hz), (0, 0, "", 0.0))
        self.assertFalse(c.HasField("seed") or c.HasField("despike_k") or c.HasField("bounds"))
        self.assertFalse(c.HasField("direction_present_hold_s") or c.HasField("direction_diffuse_weighting")
                         or c.HasField("direction_signal_weighting"))

    def test_what_the_wire_cannot_carry_is_refused(self):
        with self.assertRaisesRegex(ValueError, "no sample_rate_hz"):
            parse_session_file(text()).to_session_config()
        with self.assertRaisesRegex(ValueError, "session.accel_noise_mps2 = 0 cannot be sent"):
            parse_session_file(text({"accel_noise_mps2": 0})).to_session_config(16000.0)


@unittest.skipIf(le is None, f"localizer.engine not built: {LE_MISSING}")
class VocabularyTest(unittest.TestCase):
    def test_keys_and_names_are_the_engines(self):
        self.assertLessEqual(set(SESSION_KEYS), set(le.Session.default_options()))
        for key, names in CHOICES.items():
            for name in names:
                with self.subTest(key=key, name=name):
                    options = {key: name, "filter": "ekf"} if key == "motion_model" else {key: name}
                    try:
                        le.Session(TETRA["sensors_m"], 16000.0, **options)
                    except (ValueError, RuntimeError) as e:  # e.g. gpu without a device: not a name refusal
                        self.assertNotIn("is not one of", str(e))
        with self.assertRaisesRegex(ValueError, "is not one of"):
            le.Session(TETRA["sensors_m"], 16000.0, filter="kalman")

    def test_the_direction_keys_are_engine_options(self):
        defaults = le.Session.default_options()
        self.assertIsNone(defaults["direction_signal_weighting"])  # unset: by the array's shape
        self.assertIs(defaults["direction_diffuse_weighting"], True)
        sf = parse_session_file(text({"direction_present_hold_s": 0.0, "direction_diffuse_weighting": False,
                                      "direction_signal_weighting": True}))
        le.Session(sf.sensors_m, 16000.0, **sf.engine_options(16000.0))  # accepted as the file states them
        with self.assertRaisesRegex(TypeError, "direction_diffuse_weighting: expected True or False"):
            le.Session(TETRA["sensors_m"], 16000.0, direction_diffuse_weighting=1)


def run_cli(*args):
    return subprocess.run([CLI, *map(str, args)], capture_output=True, text=True, timeout=300)


@unittest.skipUnless(HAVE_CLI, "localizer-cli not built (LOCALIZER_CLI unset)")
class CliRefusesTheSameTest(unittest.TestCase):
    def test_the_cli_refuses_what_the_reader_refuses_and_accepts_what_it_accepts(self):
        with tempfile.TemporaryDirectory() as tmp:
            def track(session):
                path = Path(tmp) / "array.json"
                path.write_text(text(session))
                done = run_cli("track", "--array", path, "--wav", Path(tmp) / "missing.wav", "--out",
                               Path(tmp) / "out.csv")
                return path, done
            for session, key in BAD:
                with self.subTest(session=session):
                    path, done = track(session)
                    self.assertEqual(done.returncode, 1, done.stderr)
                    self.assertIn(f"{path}: session", done.stderr)
                    self.assertIn(key, done.stderr)
            for session in GOOD:
                with self.subTest(session=session):
                    path, done = track(session)  # then fails on the missing WAV, not on the file
                    self.assertNotIn(f"{path}: session", done.stderr)
                    self.assertIn("missing.wav", done.stderr)


def jsonl_rows(path):
    return [json.loads(line) for line in Path(path).read_text().splitlines() if line.strip()]


def same_number(a, b):
    """JSON's null is the CLI's NaN (JSON has none)."""
    return (b is None or math.isnan(b)) if a is None else a == b


@unittest.skipUnless(HAVE_CLI, "localizer-cli not built (LOCALIZER_CLI unset)")
@unittest.skipIf(le is None, f"localizer.engine not built: {LE_MISSING}")
class EngineMatchesCliTest(unittest.TestCase):
    SESSION = {"particles": 2048, "frame_samples": 2048, "hop_samples": 1024, "accel_noise_mps2": 0.5,
               "tdoa_sigma_s": 2.5e-05, "seed": 5, "despike_k": 4, "presence_false_alarm": 0.01}

    @classmethod
    def setUpClass(cls):
        cls.tmp = Path(tempfile.mkdtemp(prefix="localizer-session-file-test-"))
        run = subprocess.run([CLI, "simulate", "--scenario", "tetra-water", "--seed", "3", "--duration", "6",
                              "--out", str(cls.tmp)], capture_output=True, text=True, timeout=300)
        assert run.returncode == 0, run.stderr
        array = json.loads((cls.tmp / "array.json").read_text())
        array["session"] = cls.SESSION
        (cls.tmp / "session.json").write_text(json.dumps(array, indent=2))
        run = run_cli("track", "--wav", cls.tmp / "signals.wav", "--array", cls.tmp / "session.json",
                      "--format", "jsonl", "--out", cls.tmp / "estimates.jsonl", "--print-every", "0")
        assert run.returncode == 0, run.stderr
        cls.cli = jsonl_rows(cls.tmp / "estimates.jsonl")

    def test_engine_options_give_exactly_the_clis_estimates(self):
        samples, fs = localizer.audio.read(str(self.tmp / "signals.wav"))
        sf = read_session_file(self.tmp / "session.json")
        session = le.Session(sf.sensors_m, fs, **sf.engine_options(fs))
        config = session.config
        for key, value in self.SESSION.items():
            self.assertEqual(config[key], value, key)
        block = int(0.1 * fs)
        frames = np.concatenate([session.process(samples.T[i:i + block]) for i in range(0, samples.shape[1], block)])
        self.assertEqual(len(frames), len(self.cli))
        self.assertGreater(int(frames["initialised"].sum()), len(frames) // 2, "the scene was not tracked")
        for row, e in zip(frames, self.cli):
            self.assertEqual((row["frame_index"], row["t_s"]), (e["frame"], e["t_s"]))
            for name in ("initialised", "reinitialised", "source_present", "ambiguous", "far_field"):
                self.assertEqual(bool(row[name]), e[name], name)
            for name in ("presence_statistic", "presence_threshold", "range_sd_m", "nis", "ess", "tdoa_sigma_s"):
                self.assertTrue(same_number(e[name], float(row[name])), (name, e[name], row[name]))
            if e["initialised"]:
                self.assertEqual(list(row[["x_m", "y_m", "z_m"]].item()), e["position_m"])
                self.assertEqual(row["covariance"].tolist(), e["covariance"])


SERVER = os.environ.get("LOCALIZER_SERVER", "")
HAVE_SERVER = bool(SERVER) and os.access(SERVER, os.X_OK)
if HAVE_SERVER:
    from test_client import ServerFixture  # a localizer-server on a loopback port per test
else:
    ServerFixture = unittest.TestCase


@unittest.skipUnless(HAVE_CLI, "localizer-cli not built (LOCALIZER_CLI unset)")
@unittest.skipUnless(HAVE_SERVER, f"no localizer-server binary (LOCALIZER_SERVER={SERVER!r})")
class ServerMatchesCliTest(ServerFixture):
    """``to_session_config`` opens on a server the session `localizer-cli track` runs locally
    with the same file: the fields it leaves unset are the engine's defaults there too."""

    def test_a_session_opened_from_the_file_streams_the_clis_estimates(self):
        tmp = Path(self.tmp)
        run = run_cli("simulate", "--scenario", "tetra-water", "--seed", "2", "--duration", "4", "--out", tmp / "sim")
        self.assertEqual(run.returncode, 0, run.stderr)
        array = json.loads((tmp / "sim" / "array.json").read_text())
        array["session"] = EngineMatchesCliTest.SESSION
        (tmp / "session.json").write_text(json.dumps(array))
        run = run_cli("track", "--wav", tmp / "sim" / "signals.wav", "--array", tmp / "session.json", "--format",
                      "jsonl", "--out", tmp / "cli.jsonl", "--print-every", "0")
        self.assertEqual(run.returncode, 0, run.stderr)
        cli = jsonl_rows(tmp / "cli.jsonl")

        samples, fs = localizer.audio.read(str(tmp / "sim" / "signals.wav"))
        config = read_session_file(tmp / "session.json").to_session_config(fs, label="session-file")
        session = localizer.TrackSession.open(self.channel, config, timeout=60)
        for start in range(0, samples.shape[1], 4096):
            session.send(samples[:, start:start + 4096])
        session.close()
        estimates = list(session.estimates())
        self.assertEqual(session.code(), grpc.StatusCode.OK)
        self.assertEqual(len(estimates), len(cli))
        self.assertGreater(sum(e.initialised for e in estimates), len(cli) // 2, "the scene was not tracked")
        for e, want in zip(estimates, cli):
            self.assertEqual((e.frame_index, e.t_s, e.initialised), (want["frame"], want["t_s"], want["initialised"]))
            self.assertTrue(same_number(want["tdoa_sigma_s"], e.tdoa_sigma_s), (want["tdoa_sigma_s"], e.tdoa_sigma_s))
            if e.initialised:
                self.assertEqual(e.position_m.tolist(), want["position_m"])
                self.assertEqual(e.covariance.tolist(), want["covariance"])


if __name__ == "__main__":
    unittest.main()
