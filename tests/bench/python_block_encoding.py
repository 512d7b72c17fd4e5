#!/usr/bin/python3
"""How long the Python client takes to turn one numpy block into a SampleBlock, by the ways
protobuf allows: the packed bytes `localizer.sample_block` writes, against filling the
repeated float field from `.tolist()` (the old client), from the array itself and from an
`array.array`. Each way's message is checked to serialise to the same bytes first.

  PYTHONPATH=build/clients/python /usr/bin/python3 tests/bench/python_block_encoding.py \
      [--channels 4 --samples 4096 --repeat 7]

Prints the median over --repeat runs of the mean time per block, microseconds, and the
speed-up of each way over `.tolist()`. Input: seeded Gaussian noise, float32 (channels,
samples); the protobuf backend in use is printed (Debian's python3-protobuf: cpp).
"""
import argparse
import array
import statistics
import timeit

import numpy as np
from google.protobuf.internal import api_implementation

import localizer
from localizer import pb


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--channels", type=int, default=4)
    p.add_argument("--samples", type=int, default=4096)
    p.add_argument("--repeat", type=int, default=7)
    args = p.parse_args()
    x = np.random.default_rng(1).standard_normal((args.channels, args.samples)).astype(np.float32)

    def frames():
        return np.ascontiguousarray(x.T)  # the wire's frame-major order, every way pays it

    def via_tolist():
        b = pb.SampleBlock(sequence=1, channel_count=args.channels)
        b.samples.extend(frames().ravel().tolist())
        return b

    def via_ndarray():
        b = pb.SampleBlock(sequence=1, channel_count=args.channels)
        b.samples.extend(frames().ravel())
        return b

    def via_array_array():
        b = pb.SampleBlock(sequence=1, channel_count=args.channels)
        b.samples.extend(array.array("f", frames().tobytes()))
        return b

    def via_packed():  # what the package does
        return localizer.sample_block(1, x)

    ways = [("tolist", via_tolist), ("ndarray", via_ndarray), ("array.array", via_array_array),
            ("packed (localizer)", via_packed)]
    reference = via_tolist().SerializeToString()
    print(f"block {args.channels} x {args.samples} float32, protobuf backend "
          f"{api_implementation.Type()}, median of {args.repeat}")
    base = None
    for name, fn in ways:
        assert fn().SerializeToString() == reference, name
        number = max(1, int(0.2 / max(1e-6, timeit.timeit(fn, number=3) / 3)))
        us = statistics.median(t / number for t in timeit.repeat(fn, number=number, repeat=args.repeat)) * 1e6
        base = base or us
        print(f"  {name:20s} {us:9.1f} us/block   x{base / us:5.1f} vs tolist")


if __name__ == "__main__":
    main()
