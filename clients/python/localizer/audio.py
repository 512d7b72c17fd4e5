"""Reading recordings (WAV, FLAC, and whatever else libsndfile reads) into the layout
``TrackSession.send`` takes: float32 (channels, samples), channel k = sensor k.

Through python3-soundfile (libsndfile, the library localizer-cli reads WAV files with), so a
file gives the same samples here as in the CLI: integers scaled to full scale 1.0 (int16 /
32768, int32 / 2^31), float files as stored. soundfile is imported on first use, so the rest
of the package works without it.
"""
from __future__ import annotations

import os

import numpy as np

__all__ = ["read"]


def _soundfile():
    try:
        import soundfile
    except ImportError as e:
        raise ImportError("localizer.audio needs soundfile (Debian: apt-get install "
                          "python3-soundfile; elsewhere: pip install soundfile)") from e
    return soundfile


def read(path: str | os.PathLike) -> tuple[np.ndarray, float]:
    """(samples, sample_rate_hz) of the recording at ``path``: samples float32 of shape
    (channels, N), C-contiguous (so ``samples[:, a:b]`` blocks are cheap to send).

    FileNotFoundError when ``path`` does not exist; soundfile's error (naming the file) when
    libsndfile cannot read it."""
    if not os.path.exists(path):
        raise FileNotFoundError(f"localizer.audio.read: no such file: {os.fspath(path)!r}")
    data, sample_rate_hz = _soundfile().read(path, dtype="float32", always_2d=True)
    return np.ascontiguousarray(data.T), float(sample_rate_hz)
