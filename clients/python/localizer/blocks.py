"""numpy blocks to ``SampleBlock`` messages, validated before they leave the client.

Layout: a block is a 2-D array of shape (channels, samples), channel k = sensor k, as
``localizer.audio.read`` returns a recording and as the engine holds it; float32 or float64,
linear amplitude. The wire is frame-major (interleaved, as in a WAV file), so the block is
transposed on the way out.

Why the samples are packed by hand: ``SampleBlock.samples`` is a proto3 ``repeated float``,
which protobuf encodes packed (tag, byte length, raw little-endian float32s). Writing that
encoding from the array's bytes and parsing it into the message costs one copy; filling the
field through ``.extend(array.tolist())`` builds a Python float per sample: a 4 x 4096 block
takes 36-53 us packed (checks included) against 720-960 us through ``.tolist()``
(tests/bench/python_block_encoding.py, BENCHMARKS.md).
"""
from __future__ import annotations

import numpy as np
import numpy.typing as npt

from ._stubs import pb

__all__ = ["check_samples", "sample_block", "pcm16_bytes"]

_SAMPLES_TAG = b"\x1a"  # field 3 (samples), wire type 2 (length-delimited: packed)


def _varint(n: int) -> bytes:
    out = bytearray()
    while True:
        low, n = n & 0x7F, n >> 7
        if not n:
            out.append(low)
            return bytes(out)
        out.append(low | 0x80)


def check_samples(samples: npt.ArrayLike, channel_count: int | None = None) -> np.ndarray:
    """``samples`` as an ndarray of shape (channels, samples), float32 or float64, all finite,
    or a ValueError that says what is wrong and how to fix it.

    channel_count: the array's sensor count, checked when given (a (samples, channels) block
    is then named as such)."""
    x = np.asarray(samples)
    if x.dtype.kind != "f" or x.itemsize not in (4, 8):
        hint = " (int16 PCM: divide by 32768)" if x.dtype.kind in "iu" else ""
        raise ValueError(f"samples: dtype {x.dtype} is not accepted; pass float32 or float64 "
                         f"amplitudes{hint}")
    if x.ndim != 2:
        hint = " (one channel: samples[np.newaxis, :])" if x.ndim == 1 else ""
        raise ValueError(f"samples: expected a 2-D array (channels, samples), got shape {x.shape}{hint}")
    if channel_count is not None and x.shape[0] != channel_count:
        hint = (" (this looks like (samples, channels): pass samples.T)"
                if x.shape[1] == channel_count else "")
        raise ValueError(f"samples: {x.shape[0]} channels for an array of {channel_count} sensors; "
                         f"expected shape ({channel_count}, samples), got {x.shape}{hint}")
    if x.shape[1] == 0:
        raise ValueError(f"samples: the block holds no samples (shape {x.shape})")
    if not np.isfinite(x).all():
        channel, index = (int(i) for i in np.argwhere(~np.isfinite(x))[0])
        raise ValueError(f"samples: channel {channel} sample {index} is {x[channel, index]}; "
                         "every sample must be finite")
    return x


def sample_block(sequence: int, samples: npt.ArrayLike, *, channel_count: int | None = None,
                 encoding: str = "float") -> pb.SampleBlock:
    """A ``pb.SampleBlock`` from a (channels, samples) array (see ``check_samples``).

    encoding "float": ``samples`` as float32 (float64 is rounded); "pcm16": ``pcm_s16le``
    (value * 32768, clipped at full scale), half the bytes."""
    x = check_samples(samples, channel_count)
    block = pb.SampleBlock(sequence=sequence, channel_count=x.shape[0])
    if encoding == "float":
        payload = np.ascontiguousarray(x.T, dtype="<f4").tobytes()
        block.MergeFromString(_SAMPLES_TAG + _varint(len(payload)) + payload)
    elif encoding == "pcm16":
        block.pcm_s16le = pcm16_bytes(x.T)
    else:
        raise ValueError(f"encoding must be 'float' or 'pcm16', got {encoding!r}")
    return block


def pcm16_bytes(data: npt.ArrayLike) -> bytes:
    """16-bit little-endian PCM of ``data`` (any shape, amplitude 1 = full scale), C order."""
    scaled = np.clip(np.round(np.asarray(data, np.float64) * 32768.0), -32768, 32767)
    return scaled.astype("<i2").tobytes()
