#!/usr/bin/env python3
"""Memory budget: fill a localizer-server's --memory-budget-mib with the largest sessions it
admits, feed each of them, and compare the process's resident memory with the budget.

Starts one localizer-server on loopback (--memory-budget-mib BUDGET, --memory-trim 1), reads
its VmRSS as the baseline, then opens sessions of one large config (default: 16 sensors,
65536-sample frames, 262144 particles) until the server refuses one RESOURCE_EXHAUSTED.
Each session starts its track from an init_region (so its particles are in use without a
source being heard), gets --frames frames of noise (its frame ring and FFT buffers in use
too) and is waited on until its estimates arrive. Prints the baseline,
the RSS and the peak RSS (VmHWM) after, the sessions admitted, and whether RSS - baseline
stayed within BUDGET x 1.1 (the issue's bar; exit 0) or not (exit 1).

  PYTHONPATH=build/clients/python /usr/bin/python3 tests/bench/memory_budget.py --build build
"""
import argparse
import json
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import grpc
import numpy as np

import localizer_client as lc

ROOT = Path(__file__).resolve().parents[2]


def rss_kib(pid, field="VmRSS"):
    for line in Path(f"/proc/{pid}/status").read_text().splitlines():
        if line.startswith(field + ":"):
            return int(line.split()[1])
    raise RuntimeError(f"no {field} for pid {pid}")


def main(argv):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                formatter_class=argparse.ArgumentDefaultsHelpFormatter)
    p.add_argument("--build", default=str(ROOT / "build"), help="CMake build directory")
    p.add_argument("--budget-mib", type=int, default=512, help="the server's --memory-budget-mib")
    p.add_argument("--sensors", type=int, default=16, help="sensors per session")
    p.add_argument("--frame", type=int, default=65536, help="frame_samples per session")
    p.add_argument("--particles", type=int, default=262144, help="particles per session")
    p.add_argument("--frames", type=int, default=2, help="frames of noise fed to each session")
    p.add_argument("--max-sessions", type=int, default=64, help="stop opening after this many")
    args = p.parse_args(argv)

    binary = Path(args.build) / "server" / "localizer-server"
    with tempfile.TemporaryDirectory() as tmp:
        ready = Path(tmp) / "ready.json"
        server = subprocess.Popen(
            [str(binary), "--listen", "127.0.0.1:0", "--metrics-listen", "", "--ready-file", str(ready),
             "--memory-budget-mib", str(args.budget_mib), "--memory-trim", "1", "--log-level", "warn",
             "--max-particles", str(max(args.particles, 4096)), "--max-channels", str(max(args.sensors, 8))],
            stdout=open(Path(tmp) / "server.log", "wb"), stderr=subprocess.STDOUT)
        try:
            deadline = time.monotonic() + 30
            while not ready.exists():
                if server.poll() is not None or time.monotonic() > deadline:
                    sys.exit("memory_budget: the server did not start: " + (Path(tmp) / "server.log").read_text())
                time.sleep(0.05)
            target = f"127.0.0.1:{json.loads(ready.read_text())['grpc_port']}"
            time.sleep(1.5)
            baseline = rss_kib(server.pid)
            channel = lc.connect(target, options=[("grpc.use_local_subchannel_pool", 1)])
            rng = np.random.default_rng(1)
            sensors = rng.uniform(-2.0, 2.0, size=(args.sensors, 3))
            config = lc.session_config(sensors, 16000.0, frame_samples=args.frame, hop_samples=args.frame,
                                       particles=args.particles,
                                       init_region=((-5.0, -5.0, -5.0), (5.0, 5.0, 5.0)))  # a track at once
            sessions, refusal = [], None
            started = time.monotonic()
            while len(sessions) < args.max_sessions:
                if sessions and len(sessions) % 50 == 0:  # under the server's streams per connection
                    channel = lc.connect(target, options=[("grpc.use_local_subchannel_pool", 1)])
                try:
                    s = lc.TrackSession(channel, config, timeout=300)
                except grpc.RpcError as err:
                    refusal = f"{err.code().name}: {err.details()}"
                    break
                sessions.append(s)
                noise = rng.standard_normal((args.frame * args.frames, args.sensors)).astype(np.float32)
                for start in range(0, noise.shape[0], 4096):
                    s.send(noise[start:start + 4096])
            for s in sessions:  # wait for each session's estimates
                got = 0
                for _ in s.estimates():
                    got += 1
                    if got >= args.frames:
                        break
            rss, hwm = rss_kib(server.pid), rss_kib(server.pid, "VmHWM")
            for s in sessions:
                s.close()
            used_mib = (rss - baseline) / 1024.0
            peak_mib = (hwm - baseline) / 1024.0
            bar = 1.1 * args.budget_mib
            print(f"budget {args.budget_mib} MiB; sessions admitted {len(sessions)} "
                  f"({args.sensors} sensors, frame {args.frame}, {args.particles} particles); "
                  f"refused: {refusal or 'none (stopped at --max-sessions)'}")
            print(f"RSS baseline {baseline / 1024:.1f} MiB, after {rss / 1024:.1f} MiB (+{used_mib:.1f}), "
                  f"peak {hwm / 1024:.1f} MiB (+{peak_mib:.1f}); bar: +{bar:.1f} MiB; "
                  f"{time.monotonic() - started:.1f} s")
            ok = peak_mib <= bar and refusal is not None
            print("within budget + 10 %" if ok else "NOT within budget + 10 % (or never refused)")
            return 0 if ok else 1
        finally:
            server.terminate()
            server.wait(timeout=30)


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
