"""Synthetic array recordings with exactly known geometry, for tests and load tests.

A band-limited white-noise source is received at every sensor with an integer-sample delay,
plus independent white noise per sensor. ``source_with_integer_tdoas`` moves a requested
source position to the nearby point whose time differences of arrival are whole samples, so
the recording is exactly what that point would produce (no rounding between the geometry and
the samples). The signal is periodic in its length: looping it block after block keeps every
delay intact across the wrap. Recordings are (channels, samples), as ``TrackSession.send``
takes them.
"""
from __future__ import annotations

import numpy as np
import numpy.typing as npt


def tetrahedron(edge_m: float = 1.5, centre_m: npt.ArrayLike = (0.0, 0.0, 0.0)) -> np.ndarray:
    """Regular tetrahedron of edge ``edge_m`` (alternate corners of a cube): (4, 3) metres."""
    a = edge_m / (2.0 * np.sqrt(2.0))
    corners = np.array([[a, a, a], [a, -a, -a], [-a, a, -a], [-a, -a, a]])
    return corners + np.asarray(centre_m, dtype=float)


def array_positions(channels: int, edge_m: float = 1.5) -> np.ndarray:
    """The tetrahedron, then (channels > 4) extra sensors on a ring around it at +-0.4 edge height."""
    if channels < 4:
        raise ValueError(f"channels must be >= 4 (a 3-D fix needs 4 sensors), got {channels}")
    extra = [[0.6 * edge_m * np.cos(2 * np.pi * k / (channels - 4) + 0.3),
              0.6 * edge_m * np.sin(2 * np.pi * k / (channels - 4) + 0.3),
              0.4 * edge_m * (1 if k % 2 else -1)] for k in range(channels - 4)]
    return np.vstack([tetrahedron(edge_m)] + ([np.array(extra)] if extra else []))


def tdoa_s(sensors_m: npt.ArrayLike, source_m: npt.ArrayLike, sound_speed_mps: float,
           reference: int = 0) -> np.ndarray:
    """Arrival time at each sensor minus arrival at ``reference``, seconds: (C,)."""
    r = np.linalg.norm(np.asarray(sensors_m, float) - np.asarray(source_m, float), axis=1)
    return (r - r[reference]) / sound_speed_mps


def source_with_integer_tdoas(sensors_m: npt.ArrayLike, approx_source_m: npt.ArrayLike,
                              sound_speed_mps: float, sample_rate_hz: float,
                              reference: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """(source_m, tdoa_samples): the point near ``approx_source_m`` whose TDOAs are the rounded
    TDOAs of the approximate point, found by Gauss-Newton, and those integer TDOAs.

    With 4 sensors the solution is exact (3 equations, 3 unknowns); with more it is the least
    squares point and the rounded TDOAs are only approximately consistent with it.
    """
    s = np.asarray(sensors_m, float)
    target = np.round(tdoa_s(s, approx_source_m, sound_speed_mps, reference) * sample_rate_hz)
    target_s = target / sample_rate_hz
    others = [k for k in range(len(s)) if k != reference]
    p = np.asarray(approx_source_m, float).copy()
    for _ in range(100):
        r = np.linalg.norm(s - p, axis=1)
        f = ((r - r[reference]) / sound_speed_mps - target_s)[others]
        u = (p - s) / r[:, None]
        jac = ((u - u[reference]) / sound_speed_mps)[others]
        step = np.linalg.lstsq(jac, -f, rcond=None)[0]
        p += step
        if np.linalg.norm(step) < 1e-12:
            break
    return p, target.astype(int)


def broadband_at_sensors(tdoa_samples: npt.ArrayLike, n_samples: int, sample_rate_hz: float,
                         band_hz: tuple[float, float] = (200.0, 8000.0), snr_db: float = 20.0,
                         amplitude: float = 0.1, seed: int = 1) -> np.ndarray:
    """float32 array (C, n_samples): channel k is the source delayed by ``tdoa_samples[k]``
    (relative; shifted so the earliest sensor has delay 0) plus white noise ``snr_db`` below it.

    The source is Gaussian white noise band-limited to ``band_hz`` by zeroing FFT bins, scaled
    to standard deviation ``amplitude`` (0.1 keeps 16-bit PCM far from clipping). Delays are
    circular shifts, so the result is periodic with period n_samples.
    """
    rng = np.random.default_rng(seed)
    spectrum = np.fft.rfft(rng.standard_normal(n_samples))
    freqs = np.fft.rfftfreq(n_samples, 1.0 / sample_rate_hz)
    spectrum[(freqs < band_hz[0]) | (freqs > band_hz[1])] = 0.0
    source = np.fft.irfft(spectrum, n_samples)
    source *= amplitude / source.std()
    delays = np.asarray(tdoa_samples, int) - int(np.min(tdoa_samples))
    noise_std = amplitude * 10.0 ** (-snr_db / 20.0)
    out = np.empty((len(delays), n_samples), np.float32)
    for k, d in enumerate(delays):
        out[k] = np.roll(source, d) + noise_std * rng.standard_normal(n_samples)  # x[n] = s[n-d]
    return out
