"""The live web view end to end: a real localizer-server, a simulated session streamed
into it by localizer-cli, GET /sessions read as JSON, and Debian's headless Chromium
loading GET / until the track is drawn (DOM dump, then a screenshot whose pixels are
decoded and checked for the track's colour).

Environment: LOCALIZER_SERVER and LOCALIZER_CLI (the binaries; set by CTest),
LOCALIZER_CHROMIUM (optional; else `chromium` or `chromium-browser` on PATH),
LIVE_VIEW_SCREENSHOT (optional: copy the screenshot there, e.g. docs/live_view.png).
DetectionLiveViewTest also needs the Python client (LOCALIZER_PY_CLIENT_DIR, LOCALIZER_PY_GEN)
and draws a detection session's targets (LIVE_VIEW_RADAR_SCREENSHOT: copy of its screenshot).
EndedSessionLiveViewTest: a finished `--rate max` run stays listed and is drawn and replayed.
Standard library only; run with /usr/bin/python3 -m unittest -v live_view_test.
"""
import json
import os
import re
import shutil
import struct
import subprocess
import tempfile
import time
import unittest
import urllib.request
import zlib
from pathlib import Path

import ops_util
from ops_util import CLI, SERVER

CHROMIUM = (os.environ.get("LOCALIZER_CHROMIUM") or shutil.which("chromium")
            or shutil.which("chromium-browser") or "")
# The flags the headless browser runs with: no sandbox (containers, root), no GPU, and no
# background traffic (no network for users behind firewalls, none needed here).
CHROMIUM_FLAGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-background-networking",
                  "--disable-component-update", "--disable-sync", "--no-first-run",
                  "--disable-default-apps", "--disable-extensions", "--mute-audio",
                  "--hide-scrollbars", "--window-size=1200,800"]
TRACK_RGB = (0xd6, 0x27, 0x28)  # svg .track stroke in the page (live_page.cc)
MIN_TRACK_POINTS = 20


def get_json(url):
    with urllib.request.urlopen(url, timeout=5) as response:
        return response.headers.get("Content-Type", ""), json.loads(response.read())


def png_pixels(data):
    """(width, height, rows of RGB tuples) of an 8-bit RGB/RGBA non-interlaced PNG."""
    if data[:8] != b"\x89PNG\r\n\x1a\n":
        raise ValueError("not a PNG")
    pos, idat, header = 8, b"", None
    while pos < len(data):
        length, kind = struct.unpack(">I4s", data[pos:pos + 8])
        body = data[pos + 8:pos + 8 + length]
        pos += 12 + length
        if kind == b"IHDR":
            header = struct.unpack(">IIBBBBB", body)
        elif kind == b"IDAT":
            idat += body
        elif kind == b"IEND":
            break
    width, height, depth, colour, _, _, interlace = header
    if depth != 8 or colour not in (2, 6) or interlace != 0:
        raise ValueError(f"unsupported PNG (depth {depth}, colour type {colour}, interlace {interlace})")
    bpp = 3 if colour == 2 else 4
    raw = zlib.decompress(idat)
    stride = width * bpp
    rows, previous = [], bytearray(stride)
    for y in range(height):
        kind = raw[y * (stride + 1)]
        line = bytearray(raw[y * (stride + 1) + 1:(y + 1) * (stride + 1)])
        for i in range(stride):  # undo the row filter (PNG spec, section 9)
            left = line[i - bpp] if i >= bpp else 0
            up = previous[i]
            upleft = previous[i - bpp] if i >= bpp else 0
            if kind == 1:
                line[i] = (line[i] + left) & 0xff
            elif kind == 2:
                line[i] = (line[i] + up) & 0xff
            elif kind == 3:
                line[i] = (line[i] + ((left + up) >> 1)) & 0xff
            elif kind == 4:
                p = left + up - upleft
                pa, pb, pc = abs(p - left), abs(p - up), abs(p - upleft)
                pred = left if pa <= pb and pa <= pc else up if pb <= pc else upleft
                line[i] = (line[i] + pred) & 0xff
        rows.append([tuple(line[x * bpp:x * bpp + 3]) for x in range(width)])
        previous = line
    return width, height, rows


@unittest.skipUnless(ops_util.have_binaries(),
                     f"no localizer-server/localizer-cli (LOCALIZER_SERVER={SERVER!r}, LOCALIZER_CLI={CLI!r})")
class LiveViewTest(unittest.TestCase):
    """One server and one live simulated session shared by the tests (streaming takes time)."""

    @classmethod
    def setUpClass(cls):
        cls.tmp = Path(tempfile.mkdtemp(prefix="localizer-ops-"))
        try:
            cls.server = ops_util.Server(cls.tmp, "server", ["--backend", "cpu"])
        except RuntimeError:
            shutil.rmtree(cls.tmp, ignore_errors=True)
            raise
        cls.base = f"http://{cls.server.metrics_target}"
        # Real time, long enough to outlast the tests; tearDownClass stops it.
        cls.cli_log = open(cls.tmp / "cli.log", "wb")
        cls.cli = subprocess.Popen(
            [CLI, "simulate", "--scenario", "tetra-water", "--duration", "60",
             "--server", cls.server.grpc_target, "--label", "tetra-water (live view test)"],
            stdout=cls.cli_log, stderr=subprocess.STDOUT)

    @classmethod
    def tearDownClass(cls):
        ops_util.stop_process(cls.cli)
        cls.cli_log.close()
        cls.server.stop()
        shutil.rmtree(cls.tmp, ignore_errors=True)

    @classmethod
    def log_tail(cls, name):
        path = cls.tmp / name
        return path.read_bytes().decode(errors="replace")[-3000:] if path.exists() else ""

    def wait_for_track(self, points, timeout_s=60.0):
        """The one session's JSON once its track holds `points` fixes."""
        deadline = time.monotonic() + timeout_s
        doc = None
        while time.monotonic() < deadline:
            if self.cli.poll() is not None:
                self.fail(f"localizer-cli exited with {self.cli.returncode}:\n{self.log_tail('cli.log')}")
            _, doc = get_json(self.base + "/sessions")
            if doc["sessions"] and len(doc["sessions"][0]["track"]) >= points:
                return doc["sessions"][0]
            time.sleep(0.25)
        self.fail(f"no track of {points} points in {timeout_s} s; last /sessions: {json.dumps(doc)[:1000]}\n"
                  f"cli:\n{self.log_tail('cli.log')}\nserver:\n{self.server.tail()}")

    def test_sessions_json_lists_the_live_track(self):
        session = self.wait_for_track(MIN_TRACK_POINTS)
        content_type, doc = get_json(self.base + "/sessions")
        self.assertEqual(content_type, "application/json; charset=utf-8")
        self.assertEqual(doc["sessions_total"], 1)
        for key in ("id", "label", "backend", "filter_type", "attached", "sensors_m", "frames",
                    "track", "track_capacity", "model_probabilities", "presence", "present_frames"):
            self.assertIn(key, session)
        # The latest frame's source presence and ambiguity.
        self.assertIn(session["presence"]["state"], ("present", "silent", "untested"))
        self.assertIsInstance(session["presence"]["ambiguous"], bool)
        self.assertIsInstance(session["presence"]["modes"], int)
        self.assertIn("source_present", session["track"][-1])
        self.assertEqual(session["label"], "tetra-water (live view test)")
        self.assertEqual(session["backend"], "cpu")
        self.assertGreaterEqual(len(session["sensors_m"]), 4)
        self.assertTrue(all(len(p) == 3 for p in session["sensors_m"]))
        point = session["track"][-1]
        self.assertEqual(len(point["position_m"]), 3)
        self.assertTrue(all(isinstance(v, float) for v in point["position_m"]))
        self.assertLessEqual(len(session["track"]), session["track_capacity"])
        # Live: more fixes arrive while the client streams.
        time.sleep(1.5)
        _, later = get_json(self.base + "/sessions")
        later_session = later["sessions"][0]
        self.assertGreater(later_session["frames"], session["frames"])
        self.assertGreater(later_session["track"][-1]["t_s"], point["t_s"])

    @unittest.skipUnless(CHROMIUM, "no chromium (apt-get install chromium) for the headless browser check")
    def test_chromium_draws_the_track(self):
        # The copy in docs/SERVER.md (docs/live_view.png) shows a longer track (about 30 s of streaming).
        self.wait_for_track(150 if os.environ.get("LIVE_VIEW_SCREENSHOT") else MIN_TRACK_POINTS)
        profile = self.tmp / "chromium-profile"
        common = CHROMIUM_FLAGS + [f"--user-data-dir={profile}", "--virtual-time-budget=5000"]
        env = dict(os.environ, HOME=str(self.tmp))  # Chromium writes caches under HOME
        dom = subprocess.run([CHROMIUM] + common + ["--dump-dom", self.base + "/"],
                             capture_output=True, timeout=120, env=env)
        html = dom.stdout.decode(errors="replace")
        tracks = re.findall(r'<polyline class="track" data-points="(\d+)"', html)
        self.assertEqual(len(tracks), 2, f"want the x-y and x-z tracks drawn; DOM:\n{html[:3000]}\n"
                                         f"chromium stderr:\n{dom.stderr.decode(errors='replace')[-2000:]}")
        self.assertTrue(all(int(n) >= MIN_TRACK_POINTS for n in tracks), tracks)
        self.assertEqual(html.count('class="sensor"'), 2 * 4)  # tetra-water: 4 sensors, 2 panels
        # The presence badge: present, silent, or n/a when the engine tests no presence.
        self.assertRegex(html, r'<span class="presence (present|silent|untested)"')

        shot = self.tmp / "live_view.png"
        run = subprocess.run([CHROMIUM] + common + [f"--screenshot={shot}", self.base + "/"],
                             capture_output=True, timeout=120, env=env)
        self.assertTrue(shot.exists(), f"no screenshot; chromium said:\n{run.stderr.decode(errors='replace')[-2000:]}")
        width, height, rows = png_pixels(shot.read_bytes())
        self.assertEqual((width, height), (1200, 800))
        non_white = sum(1 for row in rows for p in row if min(p) < 235)
        track = sum(1 for row in rows for p in row
                    if all(abs(c - t) < 40 for c, t in zip(p, TRACK_RGB)))
        self.assertGreater(non_white, 5000, "screenshot is (nearly) blank")
        self.assertGreater(track, 100, "no track-coloured pixels in the screenshot")
        if os.environ.get("LIVE_VIEW_SCREENSHOT"):
            shutil.copyfile(shot, os.environ["LIVE_VIEW_SCREENSHOT"])


def python_client():
    """The localizer_client package, or None when its directory or stubs are missing."""
    client_dir = os.environ.get("LOCALIZER_PY_CLIENT_DIR")
    if not client_dir:
        return None
    import sys
    sys.path.insert(0, client_dir)
    try:
        import localizer_client
    except ImportError:
        return None
    return localizer_client


LC = python_client()


@unittest.skipUnless(SERVER and os.access(SERVER, os.X_OK), f"no localizer-server (LOCALIZER_SERVER={SERVER!r})")
@unittest.skipUnless(LC, "no Python client (LOCALIZER_PY_CLIENT_DIR / generated stubs)")
@unittest.skipUnless(CHROMIUM, "no chromium (apt-get install chromium) for the headless browser check")
class DetectionLiveViewTest(unittest.TestCase):
    """A detection session kept open: the page draws its targets with their ids."""

    def setUp(self):
        self.tmp = Path(tempfile.mkdtemp(prefix="localizer-ops-radar-"))
        self.addCleanup(shutil.rmtree, self.tmp, True)
        self.server = ops_util.Server(self.tmp, "server", ["--backend", "cpu"])
        self.addCleanup(self.server.stop)
        self.channel = LC.connect(self.server.grpc_target)
        self.addCleanup(self.channel.close)

    def test_chromium_draws_the_targets(self):
        import numpy as np
        session = LC.TrackSession(self.channel, LC.detection_config(label="radar (live view test)"), timeout=60)
        self.addCleanup(session.cancel)
        # Four targets 2 km apart crossing the radar's field at 150 m/s, noiseless plots.
        starts = np.array([[8000.0, -3000.0], [8000.0, -1000.0], [8000.0, 1000.0], [8000.0, 3000.0]])
        velocity = np.array([-150.0, 0.0])
        scans = 8
        for k in range(scans):
            xy = starts + velocity * 1.8182 * k
            session.send_scan(LC.scan(k, 1.8182 * k, np.hypot(xy[:, 0], xy[:, 1]), np.arctan2(xy[:, 1], xy[:, 0])))
        # Read the answers without ending the stream (leaving the generator would half-close
        # it, and a finished session leaves the view).
        answers = session.track_lists()
        lists = [next(answers) for _ in range(scans)]
        self.assertEqual([tl.sequence for tl in lists], list(range(scans)))
        _, doc = get_json(f"http://{self.server.metrics_target}/sessions")
        targets = doc["sessions"][0]["targets"]
        self.assertEqual(doc["sessions"][0]["kind"], "detections")
        self.assertEqual(sorted(t["id"] for t in targets if t["status"] == "confirmed"), [1, 2, 3, 4])

        profile = self.tmp / "chromium-profile"
        common = CHROMIUM_FLAGS + [f"--user-data-dir={profile}", "--virtual-time-budget=5000"]
        env = dict(os.environ, HOME=str(self.tmp))
        base = f"http://{self.server.metrics_target}/"
        dom = subprocess.run([CHROMIUM] + common + ["--dump-dom", base], capture_output=True, timeout=120, env=env)
        html = dom.stdout.decode(errors="replace")
        # Two panels, four confirmed targets each, labelled with their ids.
        self.assertEqual(html.count('class="target confirmed"'), 2 * 4,
                         f"DOM:\n{html[:3000]}\nchromium stderr:\n{dom.stderr.decode(errors='replace')[-2000:]}")
        self.assertIn("4 confirmed of 4 tracks", html)
        if os.environ.get("LIVE_VIEW_RADAR_SCREENSHOT"):
            shot = self.tmp / "radar.png"
            subprocess.run([CHROMIUM] + common + [f"--screenshot={shot}", base], capture_output=True, timeout=120,
                           env=env)
            shutil.copyfile(shot, os.environ["LIVE_VIEW_RADAR_SCREENSHOT"])


@unittest.skipUnless(ops_util.have_binaries(),
                     f"no localizer-server/localizer-cli (LOCALIZER_SERVER={SERVER!r}, LOCALIZER_CLI={CLI!r})")
class EndedSessionLiveViewTest(unittest.TestCase):
    """A run streamed as fast as the server takes it (it ends in well under a second) is still
    listed after it ended, with its track, and the page draws it and replays it."""

    def setUp(self):
        self.tmp = Path(tempfile.mkdtemp(prefix="localizer-ops-ended-"))
        self.addCleanup(shutil.rmtree, self.tmp, True)
        self.server = ops_util.Server(self.tmp, "server", ["--backend", "cpu"])
        self.addCleanup(self.server.stop)
        self.base = f"http://{self.server.metrics_target}"
        run = subprocess.run([CLI, "simulate", "--scenario", "tetra-water", "--duration", "10", "--rate", "max",
                              "--server", self.server.grpc_target, "--label", "ended run"],
                             capture_output=True, timeout=120)
        self.assertEqual(run.returncode, 0, run.stderr.decode(errors="replace")[-2000:])

    def test_the_ended_session_is_listed_and_drawn(self):
        _, doc = get_json(self.base + "/sessions")
        self.assertEqual(doc["sessions"], [])
        self.assertEqual(len(doc["finished"]), 1, json.dumps(doc)[:1000])
        ended = doc["finished"][0]
        self.assertEqual(ended["reason"], "finished")
        self.assertGreaterEqual(ended["finished_ago_s"], 0.0)
        session = ended["session"]
        self.assertEqual(session["label"], "ended run")
        self.assertGreaterEqual(len(session["track"]), MIN_TRACK_POINTS)
        if not CHROMIUM:
            self.skipTest("no chromium (apt-get install chromium) for the headless browser check")
        profile = self.tmp / "chromium-profile"
        env = dict(os.environ, HOME=str(self.tmp))
        common = CHROMIUM_FLAGS + [f"--user-data-dir={profile}"]

        def dom(url, budget_ms):
            run = subprocess.run([CHROMIUM] + common + [f"--virtual-time-budget={budget_ms}", "--dump-dom", url],
                                 capture_output=True, timeout=120, env=env)
            return run.stdout.decode(errors="replace")

        whole = dom(self.base + "/", 2000)
        self.assertIn('class="session finished"', whole, whole[:3000])
        self.assertIn(">replay</button>", whole)
        tracks = [int(n) for n in re.findall(r'<polyline class="track" data-points="(\d+)"', whole)]
        self.assertEqual(tracks, [len(session["track"])] * 2, whole[:3000])
        # /?replay=ID starts its replay at once: a 10 s session replays in 10 s of page time,
        # so 4 s in, part of the track is drawn, and the button says so.
        part = dom(self.base + "/?replay=" + session["id"], 4000)
        self.assertIn(">replaying ...</button>", part, part[:3000])
        drawn = [int(n) for n in re.findall(r'<polyline class="track" data-points="(\d+)"', part)]
        self.assertEqual(len(drawn), 2, part[:3000])
        self.assertTrue(0 < drawn[0] < len(session["track"]), (drawn, len(session["track"])))


if __name__ == "__main__":
    unittest.main(verbosity=2)
