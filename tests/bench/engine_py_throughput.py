#!/usr/bin/env python3
"""Throughput of localizer.engine (the Python bindings) against `localizer-cli track` on the
same audio: a simulated 4-channel recording (default: the tetra-air scenario, 48 kHz, 30 s,
written by `localizer-cli simulate`), tracked with the same config (the array file's band,
the same filter seed) by

  cli     localizer-cli track --wav signals.wav --array array.json --out /dev/null
  python  soundfile reads the WAV (float32, interleaved), Session.process in 0.25-s blocks
          (the CLI's default --block), estimates kept as numpy structured arrays

Each is run --repeats times (default 3); the median wall time and CPU time (user + system;
the CLI's from getrusage of the child) are printed with the ratio python / cli. Both read the
WAV inside the timing; the CLI also writes its CSV (to /dev/null).

    PYTHONPATH=build/clients/python /usr/bin/python3 tests/bench/engine_py_throughput.py \\
        --cli build/clients/cli/localizer-cli [--scenario tetra-air --duration 30 --repeats 3]
"""
import argparse
import json
import os
import platform
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import soundfile

import localizer.engine as le


def child_cpu_s():
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime


def run_cli(cli, wav, array):
    cpu0, wall0 = child_cpu_s(), time.perf_counter()
    subprocess.run([cli, "track", "--wav", str(wav), "--array", str(array), "--filter-seed", "1",
                    "--out", "/dev/null", "--print-every", "0"], check=True, capture_output=True)
    return time.perf_counter() - wall0, child_cpu_s() - cpu0


def run_python(wav, array_file):
    cpu0, wall0 = time.process_time(), time.perf_counter()
    array = json.loads(Path(array_file).read_text())
    samples, fs = soundfile.read(str(wav), dtype="float32", always_2d=True)  # (samples, channels)
    band = array["band_hz"]
    session = le.Session(np.array(array["sensors_m"]), float(fs), sound_speed_mps=array["sound_speed_mps"],
                         reference_sensor=array.get("reference_sensor", 0), band_low_hz=band[0],
                         band_high_hz=min(band[1], fs / 2), seed=1)
    block = round(0.25 * fs)
    frames = [session.process(samples[i:i + block]) for i in range(0, len(samples), block)]
    count = sum(len(f) for f in frames)
    return time.perf_counter() - wall0, time.process_time() - cpu0, count


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--cli", required=True)
    parser.add_argument("--scenario", default="tetra-air")
    parser.add_argument("--duration", type=float, default=30.0)
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args()
    with tempfile.TemporaryDirectory(prefix="engine-py-bench-") as tmp:
        subprocess.run([args.cli, "simulate", "--scenario", args.scenario, "--seed", "1", "--duration",
                        str(args.duration), "--out", tmp], check=True, capture_output=True)
        wav, array = Path(tmp) / "signals.wav", Path(tmp) / "array.json"
        info = soundfile.info(str(wav))
        cli, py = [], []
        for _ in range(args.repeats):  # interleaved, so that a load change hits both alike
            cli.append(run_cli(args.cli, wav, array))
            py.append(run_python(wav, array))
    med = lambda rows, k: statistics.median(r[k] for r in rows)  # noqa: E731
    print(f"machine: {platform.node()} {platform.machine()}, {os.cpu_count()} cpus, load "
          f"{os.getloadavg()[0]:.2f}; python {platform.python_version()}")
    print(f"audio: {args.scenario}, {info.channels} channels, {info.samplerate} Hz, {info.duration:.1f} s; "
          f"{py[0][2]} frames; median of {args.repeats}")
    print(f"cli:    wall {med(cli, 0):.3f} s  cpu {med(cli, 1):.3f} s")
    print(f"python: wall {med(py, 0):.3f} s  cpu {med(py, 1):.3f} s")
    print(f"ratio python/cli: wall {med(py, 0) / med(cli, 0):.3f}  cpu {med(py, 1) / med(cli, 1):.3f}")


if __name__ == "__main__":
    sys.exit(main())
