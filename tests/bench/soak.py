#!/usr/bin/env python3
"""Soak: clients/python/loadtest.py through the nginx front (deploy/nginx) for a long run,
sampling every instance's resident memory, to show that nothing grows.

Starts --instances localizer-server processes on loopback, nginx in front of them with the
shipped template, then loadtest.py (--sessions real-time sessions for --duration seconds)
against nginx; every --sample-s seconds it reads VmRSS of each server from /proc. Prints the
load test's summary, the RSS series, and per instance the change from the first sample after
the ramp (--settle-s) to the last, as a percentage (the issue's bar: flat within 5 %).

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
    p.add_argument("--settle-s", type=float, default=60.0, help="RSS baseline: first sample after this")
    p.add_argument("--processes", type=int, default=1, help="load generator processes")
    p.add_argument("--workers", type=int, default=0, help="engine threads per instance (0: one per core)")
    return p.parse_args(argv)


def free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def rss_kib(pid):
    match = re.search(r"^VmRSS:\s+(\d+) kB", Path(f"/proc/{pid}/status").read_text(), re.M)
    return int(match.group(1)) if match else 0


def start_server(binary, tmp, name, workers):
    ready = tmp / f"{name}.ready.json"
    proc = subprocess.Popen([binary, "--listen", "127.0.0.1:0", "--metrics-listen", "127.0.0.1:0",
                             "--ready-file", str(ready), "--workers", str(workers), "--log-level", "warn",
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
        instances = [start_server(str(server), tmp, f"instance{i}", args.workers) for i in range(args.instances)]
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
        settled = [s for s in samples if s[0] >= args.settle_s] or samples
        first, last = settled[0][1], samples[-1][1]
        changes = [100.0 * (b - a) / a for a, b in zip(first, last) if a]
        peak = [max(s[1][i] for s in settled) for i in range(len(first))]
        for i, (a, b, m) in enumerate(zip(first, last, peak)):
            print(f"instance{i}: {a / 1024:.1f} MiB at t={settled[0][0]:.0f} s -> {b / 1024:.1f} MiB at the last sample "
                  f"({100.0 * (b - a) / a:+.1f} %), peak {m / 1024:.1f} MiB")
        result = re.search(r"^RESULT (\{.*\})$", text, re.M)
        summary = {"rss_change_percent": changes, "load_exit": load.returncode,
                   "loadtest": json.loads(result.group(1)) if result else None}
        print("SOAK " + json.dumps(summary))
        return 0 if load.returncode == 0 and all(abs(c) <= 5.0 for c in changes) else 1
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
