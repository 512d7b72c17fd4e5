"""Shared by the ops tests: real localizer-server instances on loopback, and a simulated
scenario streamed into one by localizer-cli.

Environment (set by tests/ops/*.cmake): LOCALIZER_SERVER and LOCALIZER_CLI, the binaries.
"""
import json
import os
import signal
import socket
import subprocess
import time
import urllib.request
from pathlib import Path

SERVER = os.environ.get("LOCALIZER_SERVER", "")
CLI = os.environ.get("LOCALIZER_CLI", "")


def have_binaries():
    return all(p and os.access(p, os.X_OK) for p in (SERVER, CLI))


def free_port():
    """A TCP port free on 127.0.0.1 now (the caller binds it soon after)."""
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def stop_process(process, timeout_s=20.0):
    """SIGTERM (servers drain on it), then SIGKILL if it is still running after timeout_s."""
    if process.poll() is not None:
        return
    process.send_signal(signal.SIGTERM)
    try:
        process.wait(timeout=timeout_s)
    except subprocess.TimeoutExpired:
        process.kill()
        process.wait()


class Server:
    """One localizer-server on loopback: gRPC and metrics on ports it picks (--ready-file)."""

    def __init__(self, workdir, name, extra_args=()):
        self.dir = Path(workdir)
        self.name = name
        ready = self.dir / f"{name}.ready.json"
        self.log_path = self.dir / f"{name}.log"
        self.log = open(self.log_path, "wb")
        self.process = subprocess.Popen(
            [SERVER, "--listen", "127.0.0.1:0", "--metrics-listen", "127.0.0.1:0",
             "--ready-file", str(ready), "--workers", "2", "--log-level", "warn", *extra_args],
            stdout=self.log, stderr=subprocess.STDOUT)
        deadline = time.monotonic() + 30.0
        while not ready.exists():
            if self.process.poll() is not None:
                raise RuntimeError(f"{name} exited with {self.process.returncode}: {self.tail()}")
            if time.monotonic() > deadline:
                raise RuntimeError(f"{name} wrote no ready file in 30 s: {self.tail()}")
            time.sleep(0.05)
        info = json.loads(ready.read_text())
        self.grpc_target = f"127.0.0.1:{info['grpc_port']}"
        self.metrics_target = f"127.0.0.1:{info['metrics_port']}"

    def metrics(self):
        with urllib.request.urlopen(f"http://{self.metrics_target}/metrics", timeout=10) as r:
            return r.read().decode()

    def tail(self):
        self.log.flush()
        return self.log_path.read_bytes().decode(errors="replace")[-3000:]

    def stop(self):
        stop_process(self.process)
        self.log.close()


def stream_simulation(target, seconds=3.0, scenario="tetra-water", label="ops-test"):
    """Streams `seconds` of a simulated scenario through one session on `target` as fast as
    the server takes it; returns the CLI's output (raises when it fails)."""
    done = subprocess.run(
        [CLI, "simulate", "--scenario", scenario, "--duration", str(seconds), "--server", target,
         "--rate", "max", "--print-every", "0", "--label", label],
        capture_output=True, text=True, timeout=120)
    if done.returncode != 0:
        raise RuntimeError(f"localizer-cli simulate failed ({done.returncode}): {done.stderr[-2000:]}")
    return done.stdout


def metric_names(exposition):
    """Every sample name a text exposition can hold: each # TYPE'd family, with the
    _bucket/_sum/_count series of histograms."""
    names = set()
    for line in exposition.splitlines():
        if line.startswith("# TYPE "):
            _, _, name, kind = line.split(maxsplit=3)
            names.add(name)
            if kind == "histogram":
                names.update({name + "_bucket", name + "_sum", name + "_count"})
    return names
