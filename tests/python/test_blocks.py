"""The package localizer without a server: numpy blocks (layout, packed encoding, the
ValueErrors of bad input), estimates as dataclasses, and the deprecated localizer_client alias
giving the same bytes in its old layout.

Run from the build tree's package (LOCALIZER_PY_CLIENT_DIR, see test_client)."""
import os
import sys
import unittest
import warnings
from pathlib import Path

CLIENT_DIR = os.environ.get("LOCALIZER_PY_CLIENT_DIR") or str(
    Path(__file__).resolve().parents[2] / "clients" / "python")
sys.path.insert(0, CLIENT_DIR)

import numpy as np  # noqa: E402

import localizer  # noqa: E402
from localizer import pb  # noqa: E402

with warnings.catch_warnings():
    warnings.simplefilter("ignore", DeprecationWarning)
    import localizer_client  # noqa: E402


def reference_block(sequence, samples):
    """The SampleBlock as the old client built it: frame-major, through .tolist()."""
    block = pb.SampleBlock(sequence=sequence, channel_count=samples.shape[0])
    block.samples.extend(np.asarray(samples, np.float32).T.ravel().tolist())
    return block


class BlockTest(unittest.TestCase):
    rng = np.random.default_rng(19)

    def test_packed_encoding_equals_the_repeated_field_filled_from_a_list(self):
        for dtype in (np.float32, np.float64):
            for channels, n in ((4, 4096), (3, 1), (16, 130)):  # 130 x 16 x 4 B: a 2-byte length
                x = self.rng.standard_normal((channels, n)).astype(dtype)
                block = localizer.sample_block(7, x)
                self.assertEqual(block.SerializeToString(),
                                 reference_block(7, x).SerializeToString(), (dtype, channels, n))
                self.assertEqual(block.channel_count, channels)
                # frame-major on the wire: the first frame is every channel's first sample
                np.testing.assert_array_equal(block.samples[:channels], x[:, 0].astype(np.float32))

    def test_a_transposed_view_and_a_big_endian_array_encode_the_same(self):
        x = self.rng.standard_normal((4, 300)).astype(np.float32)
        expected = localizer.sample_block(1, x).SerializeToString()
        frames_major = np.ascontiguousarray(x.T)
        self.assertEqual(localizer.sample_block(1, frames_major.T).SerializeToString(), expected)
        self.assertEqual(localizer.sample_block(1, x.astype(">f4")).SerializeToString(), expected)

    def test_pcm16_is_interleaved_and_clipped(self):
        x = np.array([[0.5, -1.5], [0.25, 2.0]])  # channel 0, channel 1
        block = localizer.sample_block(3, x, encoding="pcm16")
        self.assertEqual(len(block.samples), 0)
        pcm = np.frombuffer(block.pcm_s16le, "<i2")
        np.testing.assert_array_equal(pcm, [16384, 8192, -32768, 32767])

    def assertRaisesWith(self, text, samples, **kwargs):
        with self.assertRaises(ValueError) as caught:
            localizer.sample_block(1, samples, **kwargs)
        self.assertIn(text, str(caught.exception))
        return str(caught.exception)

    def test_bad_blocks_are_value_errors_that_say_what_to_do(self):
        good = np.zeros((4, 64), np.float32)
        message = self.assertRaisesWith("dtype int16", good.astype(np.int16))
        self.assertIn("32768", message)
        self.assertRaisesWith("dtype complex128", good.astype(complex))
        self.assertRaisesWith("dtype float16", good.astype(np.float16))
        message = self.assertRaisesWith("expected a 2-D array (channels, samples), got shape (64,)", good[0])
        self.assertIn("np.newaxis", message)
        self.assertRaisesWith("got shape (1, 4, 64)", good[np.newaxis])
        message = self.assertRaisesWith("64 channels for an array of 4 sensors", good.T, channel_count=4)
        self.assertIn("pass samples.T", message)
        self.assertRaisesWith("3 channels for an array of 4 sensors", good[:3], channel_count=4)
        self.assertRaisesWith("no samples", good[:, :0])
        bad = good.copy()
        bad[2, 17] = np.nan
        self.assertRaisesWith("channel 2 sample 17 is nan", bad)
        bad[2, 17] = -np.inf
        self.assertRaisesWith("channel 2 sample 17 is -inf", bad)
        self.assertRaisesWith("encoding must be", good, encoding="pcm24")
        localizer.sample_block(1, good, channel_count=4)  # and the good one passes

    def test_the_alias_keeps_the_old_layout_and_bytes(self):
        x = self.rng.standard_normal((4, 256)).astype(np.float32)
        self.assertEqual(localizer_client.sample_block(5, x.T).SerializeToString(),
                         localizer.sample_block(5, x).SerializeToString())
        tdoa = [0, 6, 16, 38]
        new = localizer.synth.broadband_at_sensors(tdoa, 1024, 44100.0, seed=7)
        old = localizer_client.synth.broadband_at_sensors(tdoa, 1024, 44100.0, seed=7)
        self.assertEqual((new.shape, old.shape), ((4, 1024), (1024, 4)))
        np.testing.assert_array_equal(old, new.T)


class EstimateTest(unittest.TestCase):
    def test_an_estimate_before_the_first_fix_has_no_position(self):
        e = localizer.Estimate.from_proto(pb.Estimate(frame_index=3, sequence=2, t_s=0.1))
        self.assertEqual((e.frame_index, e.sequence, e.t_s, e.initialised), (3, 2, 0.1, False))
        self.assertIsNone(e.position_m)
        self.assertIsNone(e.velocity_mps)
        self.assertIsNone(e.covariance)
        self.assertIsNone(e.position_sd_m)
        self.assertIsNone(e.platform)
        self.assertEqual((e.sources, e.pairs, e.model_probabilities), ((), (), {}))

    def test_fields_map_to_arrays_in_si_units(self):
        cov = np.diag([4.0, 9.0, 16.0, 1.0, 1.0, 1.0])
        m = pb.Estimate(frame_index=9, initialised=True, position_m=pb.Vector3(x=1, y=2, z=-3),
                        velocity_mps=pb.Vector3(x=0.5), covariance=cov.ravel().tolist(),
                        source_present=True, ambiguous=True, modes=2, range_sd_m=0.3,
                        pairs=[pb.PairTdoa(sensor=1, delay_s=1e-3, quality=2.0)],
                        model_probabilities=[pb.ModelProbability(model="cv", probability=0.75),
                                             pb.ModelProbability(model="ct", probability=0.25)],
                        latency=pb.StageLatency(total_s=0.002))
        m.sources.add(source_id=4, status=pb.TRACK_STATUS_COASTING, direction=pb.Vector3(z=1),
                      position_m=pb.Vector3(x=7), position_covariance=np.eye(3).ravel().tolist())
        e = localizer.Estimate.from_proto(m)
        np.testing.assert_array_equal(e.position_m, [1, 2, -3])
        np.testing.assert_array_equal(e.velocity_mps, [0.5, 0, 0])
        np.testing.assert_array_equal(e.covariance, cov)
        np.testing.assert_array_equal(e.position_sd_m, [2, 3, 4])
        self.assertEqual((e.source_present, e.ambiguous, e.modes, e.range_sd_m), (True, True, 2, 0.3))
        self.assertEqual(e.pairs, (localizer.PairTdoa(1, 1e-3, 2.0, 0.0),))
        self.assertEqual(e.model_probabilities, {"cv": 0.75, "ct": 0.25})
        self.assertEqual(e.latency.total_s, 0.002)
        source = e.sources[0]
        self.assertEqual((source.id, source.status), (4, "coasting"))
        np.testing.assert_array_equal(source.position_m, [7, 0, 0])
        self.assertEqual(source.position_covariance.shape, (3, 3))
        self.assertIs(e.raw, m)
        with self.assertRaises(ValueError):  # read-only: the dataclass is frozen all the way down
            e.position_m[0] = 0.0
        with self.assertRaises(AttributeError):
            e.t_s = 1.0

    def test_a_locate_response_without_a_fix(self):
        fix = localizer.Fix.from_proto(pb.LocateResponse(pairs=[pb.PairTdoa(sensor=2)], tdoa_s=0.01))
        self.assertFalse(fix.fix_found)
        self.assertIsNone(fix.position_m)
        self.assertEqual((len(fix.pairs), fix.gcc_wall_s), (1, 0.01))


if __name__ == "__main__":
    unittest.main(verbosity=2)
