"""tests/clients/room_scene_score.py on a hand-made scene: heard, false and lingering rows
counted as its docstring says (a present row within the tolerance of a talker is that
talker's; one near talkers that are all silent, past the grace after their stop, lingers)."""
import csv
import os
import sys
import tempfile
import unittest

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), '..', 'clients'))
import room_scene_score  # noqa: E402

HOP_S = 0.016


def write_csv(path, header, rows):
    with open(path, 'w', newline='') as f:
        w = csv.writer(f)
        w.writerow(header)
        w.writerows(rows)


class RoomSceneScoreTest(unittest.TestCase):
    def setUp(self):
        self.dir = tempfile.TemporaryDirectory()
        d = self.dir.name
        # Two talkers on a line: cone angles 0.5 and 1.5 rad. Talker 0 sounds over [0, 1] s,
        # talker 1 over [0.5, 2] s.
        write_csv(f'{d}/sources.csv', ['source', 'azimuth_rad', 'elevation_rad', 'cone_angle_rad'],
                  [[0, '', '', 0.5], [1, '', '', 1.5]])
        write_csv(f'{d}/sounding.csv', ['source', 'on_s', 'off_s'], [[0, 0.0, 1.0], [1, 0.5, 2.0]])
        rows = []
        self.frames = [round(i * HOP_S, 6) for i in range(int(3.0 / HOP_S))]
        for t in self.frames:
            rows.append([t, '', '', '', '', ''])  # every frame appears
            if 0.2 <= t <= 1.5:  # a track on talker 0, present until 1.5 s: lingers after 1.1 s
                rows.append([t, '1', 'confirmed', '1', '', 0.52])
            if abs(t - 0.32) < 1e-9:  # one present row far from both talkers: false
                rows.append([t, '2', 'confirmed', '1', '', 2.6])
        write_csv(f'{d}/track.csv', ['t_s', 'source_id', 'status', 'source_present', 'azimuth_rad',
                                     'cone_angle_rad'], rows)

    def tearDown(self):
        self.dir.cleanup()

    def test_heard_false_and_lingering_rows(self):
        r = room_scene_score.score(self.dir.name, f'{self.dir.name}/track.csv', line=True)
        in_range = lambda lo, hi: sum(1 for t in self.frames if lo <= t <= hi)
        talker0 = r['talkers'][0]
        self.assertEqual(talker0['sounding'], in_range(0.0, 1.0))
        self.assertEqual(talker0['heard'], in_range(0.2, 1.0))
        self.assertEqual(r['talkers'][1]['heard'], 0)
        self.assertEqual(r['false_rows'], 1)
        # Present at talker 0 after 1.0 + LINGER_GRACE_S while it is silent (talker 1 is far).
        grace = room_scene_score.LINGER_GRACE_S
        self.assertEqual(r['lingering_rows'], sum(1 for t in self.frames if 1.0 + grace < t <= 1.5))
        minutes = len(self.frames) * HOP_S / 60.0
        self.assertAlmostEqual(r['lingering_s_per_min'], r['lingering_rows'] * HOP_S / minutes)


if __name__ == '__main__':
    unittest.main()
