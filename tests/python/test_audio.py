"""localizer.audio.read on what localizer-cli writes and reads.

`localizer-cli simulate` writes signals.wav (float32, channel k = sensor k). The reader must
give (channels, samples) float32 equal to (1) the WAV's data chunk decoded here by hand from
the RIFF layout, and (2) what the CLI itself reads: the reader's samples, written back as
headerless f32le and tracked with `track --raw`, give the same estimates CSV as `track --wav`
on the file (the CLI reads both paths into the same engine; its delay columns carry every
digit, so a changed sample, order or scale shows). A FLAC copy reads back within 16-bit
quantisation. Skips (with the reason) without soundfile or localizer-cli.
"""
import csv
import io
import json
import os
import shutil
import struct
import subprocess
import sys
import tempfile
import unittest
from pathlib import Path

CLIENT_DIR = os.environ.get("LOCALIZER_PY_CLIENT_DIR") or str(
    Path(__file__).resolve().parents[2] / "clients" / "python")
sys.path.insert(0, CLIENT_DIR)

import numpy as np  # noqa: E402

import localizer.audio  # noqa: E402

CLI = os.environ.get("LOCALIZER_CLI", "")
try:
    import soundfile
except ImportError:
    soundfile = None

WAVE_FORMAT_IEEE_FLOAT, WAVE_FORMAT_EXTENSIBLE = 3, 0xFFFE
TIMING_COLUMNS = {"tdoa_ms", "filter_ms"}  # wall time: differs run to run


def wav_float32_by_hand(path):
    """(channels, N) float32 and the rate of a float32 WAV, from its RIFF chunks."""
    data = Path(path).read_bytes()
    assert data[:4] == b"RIFF" and data[8:12] == b"WAVE", "not a RIFF/WAVE file"
    offset, fmt, samples = 12, None, None
    while offset + 8 <= len(data):
        tag, size = data[offset:offset + 4], struct.unpack_from("<I", data, offset + 4)[0]
        body = data[offset + 8:offset + 8 + size]
        if tag == b"fmt ":
            fmt = struct.unpack_from("<HHIIHH", body)
            if fmt[0] == WAVE_FORMAT_EXTENSIBLE:  # the real format is the GUID's first 2 bytes
                fmt = (struct.unpack_from("<H", body, 24)[0],) + fmt[1:]
        elif tag == b"data":
            samples = body
        offset += 8 + size + (size & 1)
    tag, channels, rate, _, _, bits = fmt
    assert (tag, bits) == (WAVE_FORMAT_IEEE_FLOAT, 32), f"not float32: format {tag}, {bits} bits"
    return np.frombuffer(samples, "<f4").reshape(-1, channels).T, float(rate)


def csv_without_timing(path):
    rows = list(csv.DictReader(io.StringIO(Path(path).read_text())))
    return [{k: v for k, v in row.items() if k not in TIMING_COLUMNS} for row in rows]


@unittest.skipUnless(soundfile, "python3-soundfile not installed (deploy/install.sh)")
@unittest.skipUnless(CLI and os.access(CLI, os.X_OK), f"no localizer-cli binary (LOCALIZER_CLI={CLI!r})")
class AudioReadTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.tmp = Path(tempfile.mkdtemp(prefix="localizer-pyaudio-"))
        cls.run_cli("simulate", "--scenario", "tetra-water", "--seed", "3", "--duration", "2",
                    "--out", str(cls.tmp / "sim"))
        cls.wav = cls.tmp / "sim" / "signals.wav"
        cls.array = json.loads((cls.tmp / "sim" / "array.json").read_text())

    @classmethod
    def tearDownClass(cls):
        shutil.rmtree(cls.tmp, ignore_errors=True)

    @staticmethod
    def run_cli(*args):
        done = subprocess.run([CLI, *args], capture_output=True, text=True, timeout=120)
        if done.returncode != 0:
            raise AssertionError(f"localizer-cli {' '.join(args)}: exit {done.returncode}\n{done.stderr}")
        return done

    def test_wav_reads_as_channels_by_samples_equal_to_the_file(self):
        samples, rate = localizer.audio.read(self.wav)
        self.assertEqual(samples.dtype, np.float32)
        self.assertTrue(samples.flags.c_contiguous)
        self.assertEqual(samples.shape, (len(self.array["sensors_m"]), int(2 * rate)))
        self.assertEqual(rate, self.array["sample_rate_hz"])
        by_hand, by_hand_rate = wav_float32_by_hand(self.wav)
        self.assertEqual(rate, by_hand_rate)
        np.testing.assert_array_equal(samples, by_hand)
        self.assertGreater(np.abs(samples).max(), 0.0)

    def test_the_cli_reads_the_same_samples(self):
        samples, rate = localizer.audio.read(self.wav)
        raw = self.tmp / "signals.f32"
        raw.write_bytes(np.ascontiguousarray(samples.T, "<f4").tobytes())
        array_json = str(self.tmp / "sim" / "array.json")
        self.run_cli("track", "--array", array_json, "--wav", str(self.wav), "--out", str(self.tmp / "wav.csv"))
        self.run_cli("track", "--array", array_json, "--raw", str(raw), "--raw-format", "f32le",
                     "--channels", str(samples.shape[0]), "--sample-rate", repr(rate),
                     "--out", str(self.tmp / "raw.csv"))
        from_wav, from_raw = csv_without_timing(self.tmp / "wav.csv"), csv_without_timing(self.tmp / "raw.csv")
        self.assertGreater(len(from_wav), 5)
        self.assertEqual(from_raw, from_wav)

    def test_flac_reads_back_within_16_bit_quantisation(self):
        samples, rate = localizer.audio.read(self.wav)
        flac = self.tmp / "signals.flac"
        soundfile.write(flac, samples.T, int(rate), subtype="PCM_16")
        back, back_rate = localizer.audio.read(flac)
        self.assertEqual((back.shape, back.dtype, back_rate), (samples.shape, np.float32, rate))
        # libsndfile writes x * 32767 and reads n / 32768: within 1.5 steps for |x| <= 1
        np.testing.assert_allclose(back, samples, rtol=0, atol=1.5 / 32768)

    def test_a_missing_file_is_named(self):
        with self.assertRaises(FileNotFoundError) as caught:
            localizer.audio.read(self.tmp / "nothing.wav")
        self.assertIn("nothing.wav", str(caught.exception))


if __name__ == "__main__":
    unittest.main(verbosity=2)
