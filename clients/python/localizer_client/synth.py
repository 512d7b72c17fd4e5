"""Deprecated: ``localizer.synth`` with the old (samples, channels) recordings."""
import numpy as np

from localizer import synth as _synth
from localizer.synth import array_positions, source_with_integer_tdoas, tdoa_s, tetrahedron

__all__ = ["tetrahedron", "array_positions", "tdoa_s", "source_with_integer_tdoas",
           "broadband_at_sensors"]


def broadband_at_sensors(tdoa_samples, n_samples, sample_rate_hz, band_hz=(200.0, 8000.0),
                         snr_db=20.0, amplitude=0.1, seed=1):
    """float32 (n_samples, C): ``localizer.synth.broadband_at_sensors`` transposed (same values)."""
    return np.ascontiguousarray(_synth.broadband_at_sensors(
        tdoa_samples, n_samples, sample_rate_hz, band_hz=band_hz, snr_db=snr_db,
        amplitude=amplitude, seed=seed).T)
