#!/usr/bin/env python3
"""Soak: clients/python/loadtest.py through the nginx front (deploy/nginx) for a long run,
sampling every instance's resident memory, to show that nothing grows.

Starts --instances localizer-server processes on loopback, nginx in front of them with the
shipped template, then loadtest.py (--sessions real-time sessions for --duration seconds)
against nginx; every --sample-s seconds it reads VmRSS of each server from /proc. Prints the
load test's summary, the RSS series, and per instance how RSS moved after the ramp
(--settle-s): the change from the median of the first --window-s seconds of samples to the
median of the last --window-s, and the least-squares trend over all of them per 10 minutes,
both as percentages (the issue's bar: flat within 5 %). Medians, not single samples: the
server returns free heap pages every --memory-trim seconds, so RSS saw-tooths by a few
per cent and one sample against another mostly measures where each fell in that cycle.

  /usr/bin/python3 tests/bench/soak.py --build build --sessions 200 --duration 600
Needs nginx (Debian nginx-light) and a build with the Python stubs (build/clients/python).
"""
import argparse
import json
import re
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


def parse_args(argv):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                formatter_class=argparse.ArgumentDefaultsHelpFormatter)
    p.add_argument("--build", default=str(ROOT / "build"), help="CMake build directory")
    p.add_argument("--instances", type=int, default=2, help="localizer-server processes behind nginx")
    p.add_argument("--sessions", type=int, default=200, help="concurrent real-time sessions")
    p.add_argument("--duration", type=float, default=600.0, help="seconds each session streams")
    p.add_argument("--ramp", type=float, default=20.0, help="seconds over which sessions start")
    p.add_argument("--sample-s", type=float, default=10.0, help="seconds between RSS samples")
    p.add_argument("--settle-s", type=float, default=60.0, help="RSS is judged from this time on")
    p.add_argument("--window-s", type=float, default=120.0,
                   help="RSS change: median of the first window after settling vs the last")
    p.add_argument("--processes", type=int, default=1, help="load generator processes")
    p.add_argument("--workers", type=int, default=0, help="engine threads per instance (0: one per core)")
    p.add_argument("--memory-trim", type=float, default=30.0,
                   help="the servers' --memory-trim: seconds between returns of free heap pages (0: never)")
    return p.parse_args(argv)


def free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def rss_kib(pid):
    match = re.search(r"^VmRSS:\s+(\d+) kB", Path(f"/proc/{pid}/status").read_text(), re.M)
    return int(match.group(1)) if match else 0


def median(values):
    v = sorted(values)
    return 0.5 * (v[(len(v) - 1) // 2] + v[len(v) // 2])


def rss_movement(samples, settle_s, window_s):
    """Per instance: (median of the last window - median of the first) / first, in %, and the
    least-squares slope over the settled samples in % of their mean per 10 minutes; prints
    both with the minimum and peak."""
    settled = [s for s in samples if s[0] >= settle_s] or samples
    t0, t1 = settled[0][0], settled[-1][0]
    changes, trends = [], []
    for i in range(len(settled[0][1])):
        series = [(t, rss[i] / 1024.0) for t, rss in settled]
        head = median([r for t, r in series if t <= t0 + window_s])
        tail = median([r for t, r in series if t >= t1 - window_s])
        tm = sum(t for t, _ in series) / len(series)
        rm = sum(r for _, r in series) / len(series)
        var_t = sum((t - tm) ** 2 for t, _ in series)
        slope = sum((t - tm) * (r - rm) for t, r in series) / var_t if var_t > 0 else 0.0
        changes.append(100.0 * (tail - head) / head)
        trends.append(100.0 * slope * 600.0 / rm)
        print(f"instance{i}: median {head:.1f} MiB over t={t0:.0f}..{t0 + window_s:.0f} s -> {tail:.1f} MiB over the "
              f"last {window_s:.0f} s ({changes[-1]:+.1f} %); trend {trends[-1]:+.1f} % per 10 min; "
              f"min {min(r for _, r in series):.1f}, peak {max(r for _, r in series):.1f} MiB")
    return changes, trends


def start_server(binary, tmp, name, workers, memory_trim_s):
    ready = tmp / f"{name}.ready.json"
    proc = subprocess.Popen([binary, "--listen", "127.0.0.1:0", "--metrics-listen", "127.0.0.1:0",
                             "--ready-file", str(ready), "--workers", str(workers), "--log-level", "warn",
                             "--memory-trim", str(memory_trim_s),
                             "--max-sessions", "4096"],
                            stdout=open(tmp / f"{name}.log", "wb"), stderr=subprocess.STDOUT)
    deadline = time.monotonic() + 30
    while not ready.exists():
        if proc.poll() is not None or time.monotonic() > deadline:
            sys.exit(f"soak: {name} did not start; see {tmp / (name + '.log')}")
        time.sleep(0.05)
    return proc, f"127.0.0.1:{json.loads(ready.read_text())['grpc_port']}"


def start_nginx(nginx, tmp, backends):
    for d in ("logs", "temp"):
        (tmp / d).mkdir(exist_ok=True)
    listen = f"127.0.0.1:{free_port()}"
    conf = tmp / "localizer.conf"
    conf.write_text((ROOT / "deploy" / "nginx" / "localizer.conf").read_text()
                    .replace("@LISTEN@", listen)
                    .replace("@BACKENDS@", " ".join(f"server {b};" for b in backends)))
    proc = subprocess.Popen([nginx, "-e", "stderr", "-p", f"{tmp}/", "-c", str(conf), "-g",
                             f"daemon off; pid {tmp}/nginx.pid; error_log stderr warn;"],
                            stdout=open(tmp / "nginx.log", "wb"), stderr=subprocess.STDOUT)
    host, port = listen.rsplit(":", 1)
    deadline = time.monotonic() + 10
    while time.monotonic() < deadline:
        try:
            socket.create_connection((host, int(port)), timeout=0.2).close()
            return proc, listen
        except OSError:
            if proc.poll() is not None:
                break
            time.sleep(0.05)
    sys.exit(f"soak: nginx did not start; see {tmp / 'nginx.log'}")


def main(argv):
    args = parse_args(argv)
    build = Path(args.build)
    server = build / "server" / "localizer-server"
    loadtest = build / "clients" / "python" / "loadtest.py"
    nginx = shutil.which("nginx") or "/usr/sbin/nginx"
    for path in (server, loadtest, Path(nginx)):
        if not path.exists():
            sys.exit(f"soak: {path} not found")
    tmp = Path(tempfile.mkdtemp(prefix="localizer-soak-"))
    procs = []
    try:
        instances = [start_server(str(server), tmp, f"instance{i}", args.workers, args.memory_trim) for i in range(args.instances)]
        procs += [p for p, _ in instances]
        front, target = start_nginx(nginx, tmp, [t for _, t in instances])
        procs.append(front)
        print(f"soak: {args.instances} instances behind nginx at {target}; {args.sessions} sessions for "
              f"{args.duration:.0f} s (logs in {tmp})", flush=True)
        load_log = tmp / "loadtest.log"
        load = subprocess.Popen(
            ["/usr/bin/python3", str(loadtest), "--target", target, "--sessions", str(args.sessions),
             "--duration", str(args.duration), "--rate", "realtime", "--ramp", str(args.ramp),
             "--processes", str(args.processes)],
            stdout=open(load_log, "w"), stderr=subprocess.STDOUT)
        procs.append(load)
        samples = []  # (t_s, [rss_kib per instance])
        start = time.monotonic()
        while load.poll() is None:
            samples.append((time.monotonic() - start, [rss_kib(p.pid) for p, _ in instances]))
            progress = load_log.read_text().strip().splitlines()[-1:] or [""]
            print(f"t={samples[-1][0]:6.0f} s  RSS MiB " + " ".join(f"{r / 1024:.1f}" for r in samples[-1][1]) +
                  f"  | {progress[0][:100]}", flush=True)
            deadline = time.monotonic() + args.sample_s
            while load.poll() is None and time.monotonic() < deadline:
                time.sleep(0.2)
        after = [rss_kib(p.pid) for p, _ in instances]  # sessions closed
        text = load_log.read_text()
        print(text[-2500:])
        print("\nRSS (MiB) per instance:")
        for t, rss in samples:
            print(f"  t={t:6.0f} s  " + "  ".join(f"{r / 1024:7.1f}" for r in rss))
        print("  after the sessions closed: " + "  ".join(f"{r / 1024:7.1f}" for r in after))
        changes, trends = rss_movement(samples, args.settle_s, args.window_s)
        summary = {"rss_change_percent": changes, "rss_trend_percent_per_10min": trends,
                   "load_exit": load.returncode}
        result = re.search(r"^RESULT (\{.*\})$", text, re.M)
        summary["loadtest"] = json.loads(result.group(1)) if result else None
        print("SOAK " + json.dumps(summary))
        flat = all(abs(c) <= 5.0 for c in changes + trends)
        return 0 if load.returncode == 0 and flat else 1
    finally:
        for p in reversed(procs):
            if p.poll() is None:
                p.send_signal(signal.SIGTERM)
                try:
                    p.wait(timeout=20)
                except subprocess.TimeoutExpired:
                    p.kill()


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
