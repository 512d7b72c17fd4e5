"""The Python client's source sessions against a real localizer-server: directions from a
planar array, and positions per source that need their constraints (source_side,
source_plane). The server fixture and the constants are test_client's."""
import os
import unittest

import grpc
import numpy as np

from test_client import BAND_HZ, BLOCK, FRAME, FS_HZ, HOP, SERVER, SOUND_SPEED_MPS, ServerFixture, lc, synth


@unittest.skipUnless(SERVER and os.access(SERVER, os.X_OK),
                     f"no localizer-server binary (LOCALIZER_SERVER={SERVER!r})")
class SourcesServerTest(ServerFixture):
    def test_planar_array_session_reports_directions(self):
        # A 1 m square in the x-y plane (coplanar: no position) and a far source above it: a
        # plane wave from `toward`, each sensor's delay rounded to whole samples.
        square = np.array([[0.5, 0, 0], [0, 0.5, 0], [-0.5, 0, 0], [0, -0.5, 0]])
        toward = np.array([8.0, 6.0, 5.0]) / np.linalg.norm([8.0, 6.0, 5.0])
        lag_per_direction = -(square - square[0]) * FS_HZ / SOUND_SPEED_MPS  # samples per unit u
        tdoa = np.round(lag_per_direction @ toward).astype(int)
        # The direction those whole-sample delays say (least squares in the board's plane,
        # above it): what the session should find.
        in_plane = np.linalg.lstsq(lag_per_direction[1:, :2], tdoa[1:], rcond=None)[0]
        truth = np.append(in_plane, np.sqrt(1.0 - in_plane @ in_plane))
        audio = synth.broadband_at_sensors(tdoa, 10 * BLOCK, FS_HZ, band_hz=BAND_HZ, snr_db=20.0, seed=3)
        cfg = lc.session_config(square, FS_HZ, sound_speed_mps=SOUND_SPEED_MPS, frame_samples=FRAME,
                                hop_samples=HOP, band_hz=BAND_HZ, seed=1, label="py-planar",
                                max_sources=2, source_side=(0, 0, 1))  # the source is above the board
        self.assertEqual(cfg.localization, "")  # auto: the server picks directions for a board
        session = lc.TrackSession(self.channel, cfg, timeout=60)
        self.assertEqual(session.opened.array_shape, "planar")
        self.assertEqual(session.opened.localization, "direction")
        self.stream(session, [(k + 1, audio[k * BLOCK:(k + 1) * BLOCK]) for k in range(10)])
        estimates = list(session.estimates())
        self.assertEqual(session.code(), grpc.StatusCode.OK)
        last = estimates[-1]
        self.assertEqual(len(last.sources), 1, [[(s.source_id, s.status) for s in e.sources] for e in estimates])
        found = last.sources[0]
        self.assertEqual(found.status, lc.pb.TRACK_STATUS_CONFIRMED)
        got = np.array([found.direction.x, found.direction.y, found.direction.z])
        angle_deg = np.degrees(np.arccos(np.clip(truth @ got, -1.0, 1.0)))
        self.assertLess(angle_deg, 3.0, f"direction {got} vs {truth}")
        self.assertFalse(last.initialised)  # no position from a planar array
        self.assertEqual(session.opened.effective_config.max_sources, 2)
        rows = lc.sources(last)
        self.assertEqual([(r["id"], r["status"]) for r in rows], [(found.source_id, "confirmed")])
        self.assertAlmostEqual(rows[0]["azimuth_rad"], found.azimuth_rad)
        self.assertTrue(np.isnan(rows[0]["cone_angle_rad"]))  # a board has no cone angle

    def test_positions_from_a_board_and_a_line_need_their_constraints(self):
        # The same 1 m square asked for positions on its upper side: a plane wave is a source at
        # infinite range, so each source says its range sd and gives no position.
        square = np.array([[0.5, 0, 0], [0, 0.5, 0], [-0.5, 0, 0], [0, -0.5, 0]])
        toward = np.array([8.0, 6.0, 5.0]) / np.linalg.norm([8.0, 6.0, 5.0])
        tdoa = np.round(-(square - square[0]) * FS_HZ / SOUND_SPEED_MPS @ toward).astype(int)
        audio = synth.broadband_at_sensors(tdoa, 10 * BLOCK, FS_HZ, band_hz=BAND_HZ, snr_db=20.0, seed=5)
        cfg = lc.session_config(square, FS_HZ, sound_speed_mps=SOUND_SPEED_MPS, frame_samples=FRAME,
                                hop_samples=HOP, band_hz=BAND_HZ, seed=1, label="py-board-positions",
                                localization="position", max_sources=1, source_side=(0, 0, 1))
        session = lc.TrackSession(self.channel, cfg, timeout=60)
        self.assertEqual((session.opened.array_shape, session.opened.localization), ("planar", "position"))
        self.stream(session, [(k + 1, audio[k * BLOCK:(k + 1) * BLOCK]) for k in range(10)])
        estimates = list(session.estimates())
        self.assertEqual(session.code(), grpc.StatusCode.OK)
        heard = [r for e in estimates for r in lc.sources(e) if r["source_present"]]
        self.assertTrue(heard)
        self.assertTrue(all(r["position_m"] is None for r in heard))  # far field: direction only
        self.assertTrue(all(r["range_sd_m"] > 0.0 for r in heard))
        # A line asked for positions without its plane is refused naming it; with the plane, the
        # effective config echoes it.
        line = np.array([[0.1 * k, 0.0, 1.5] for k in range(4)])
        bad = lc.session_config(line, FS_HZ, sound_speed_mps=SOUND_SPEED_MPS, localization="position",
                                source_side=(0, 1, 0), label="py-line-no-plane")
        with self.assertRaises(grpc.RpcError) as caught:
            lc.TrackSession(self.channel, bad, timeout=30)
        self.assertEqual(caught.exception.code(), grpc.StatusCode.INVALID_ARGUMENT)
        self.assertIn("source_plane", caught.exception.details())
        good = lc.session_config(line, FS_HZ, sound_speed_mps=SOUND_SPEED_MPS, source_side=(0, 1, 0),
                                 source_plane=((0, 0, 1.5), (0, 0, 1)), label="py-line-plane")
        line_session = lc.TrackSession(self.channel, good, timeout=30)
        self.assertEqual((line_session.opened.array_shape, line_session.opened.localization), ("linear", "position"))
        self.assertEqual(line_session.opened.effective_config.source_plane.normal.z, 1.0)
        self.assertEqual(line_session.opened.effective_config.source_plane.point_m.z, 1.5)
        line_session.close()
        list(line_session.estimates())
