#!/usr/bin/python3
"""Service capacity and overhead on this machine: starts localizer-server, drives it with a
load generator (clients/python/loadtest.py, or with --generator cpp build/clients/localizer-loadgen)
and reads the server's own CPU time (/proc) and metrics.

For each session count it prints one row: blocks/s, estimate latency p50/p95/p99, errors
and rejections, and the server's CPU per block split into the engine (worker-thread CPU
inside Session::Process, localizer_engine_cpu_seconds_total) and everything else
(decode, queue, encode, gRPC, kernel): the "outside the engine" figure.

  tests/bench/service_capacity.py --build build --sessions 100,200,300 --duration 20
  tests/bench/service_capacity.py --build build --sessions 4 --rate max --particles 256
  tests/bench/service_capacity.py --bare --sessions 200    # gRPC alone: the overhead's floor

  tests/bench/service_capacity.py --sessions 60 --security plain,tls,mtls-token   # TLS's cost
  tests/bench/service_capacity.py --sessions 200,300 --generator cpp    # the C++ generator

--generator: python (loadtest.py, the default) or cpp (localizer-loadgen: gRPC's callback API,
many sessions per thread, --threads of them). Both get the same session parameters; each row
also shows the generator's own CPU (getrusage of the finished child), per block and in cores,
so that the two can be set side by side.

--security runs every session count once per mode, side by side: plain (plaintext gRPC),
tls (server certificate; the load generator verifies it), mtls-token (mutual TLS and a bearer
token on every stream). The certificates and tokens come from deploy/tls/make_test_certs.sh in
a temporary directory.

--bare drives build/tests/bench/bare_stream_server instead: the same Track protocol with no
engine, no worker pool and no sessions (two small estimates per block, written from the
gRPC thread), so its CPU per block is what gRPC and the kernel cost by themselves.
Wake-ups: vcs/block and ivcs/block are the server's voluntary context switches (a thread
slept and was woken: the hand-offs) and involuntary ones (preempted) per block over the
generator's run, summed over its threads from /proc/<pid>/task/*/status (perf is not
permitted on every machine); the RESULT line also splits the voluntary ones by thread name
(nexting_thread: gRPC's callback threads; the binary's name: the worker pool).
--warmup S starts the server's figures S seconds into the generator's run (heap warm-up
excluded: minflt/block, the server's minor page faults per block, shows the heap still growing).
--server BINARY runs another build of localizer-server, so that two builds can be run
alternately in the same minutes (issue 20). --server-arg and --generator-arg pass one more
flag to the server or the load generator (repeatable), e.g. --generator-arg=--hop=4096: one
frame, so one estimate, per 4096-sample block.

A fresh server is started for every row. Exit 0 unless a run failed to start.
"""
import argparse
import json
import os
import re
import signal
import subprocess
import sys
import resource
import tempfile
import time
import urllib.request


def process_cpu_s(pid):
    with open(f"/proc/{pid}/stat") as f:
        fields = f.read().rsplit(")", 1)[1].split()
    ticks = int(fields[11]) + int(fields[12])  # utime + stime
    return ticks / os.sysconf("SC_CLK_TCK")


def process_minor_faults(pid):
    """Minor page faults of the whole process so far: a heap that grows touches new pages
    (one fault per 4 KiB first touched), so faults per block falls to ~0 once it stops."""
    with open(f"/proc/{pid}/stat") as f:
        return int(f.read().rsplit(")", 1)[1].split()[7])


def scrape(port):
    text = urllib.request.urlopen(f"http://127.0.0.1:{port}/metrics", timeout=5).read().decode()
    def value(series):
        m = re.search(r"^" + re.escape(series) + r" (\S+)$", text, re.M)
        return float(m.group(1)) if m else 0.0
    return {"engine_cpu_s": value("localizer_engine_cpu_seconds_total"),
            "blocks": value("localizer_blocks_total")}


def start_server(binary, bare, workers, extra):
    ready = tempfile.mktemp(prefix="localizer-ready-")
    cmd = [binary, "--listen", "127.0.0.1:0", "--ready-file", ready]
    if not bare:
        cmd += ["--metrics-listen", "127.0.0.1:0", "--log-level", "warn", "--max-sessions", "4096"]
        cmd += (["--workers", str(workers)] if workers else []) + extra
    proc = subprocess.Popen(cmd)
    deadline = time.time() + 20
    while not os.path.exists(ready):
        if proc.poll() is not None or time.time() > deadline:
            raise RuntimeError("server did not start: " + " ".join(cmd))
        time.sleep(0.05)
    with open(ready) as f:
        ports = json.load(f)
    os.unlink(ready)
    return proc, ports


def security_flags(mode, pki):
    """(server flags, loadtest flags) of a --security mode."""
    if mode == "plain":
        return [], []
    server = ["--tls-cert", f"{pki}/server.crt", "--tls-key", f"{pki}/server.key"]
    client = ["--tls-ca", f"{pki}/ca.crt"]
    if mode == "mtls-token":
        server += ["--tls-client-ca", f"{pki}/ca.crt", "--auth-token-file", f"{pki}/tokens"]
        client += ["--tls-cert", f"{pki}/client.crt", "--tls-key", f"{pki}/client.key",
                   "--auth-token-file", f"{pki}/client.token"]
    return server, client


def generator_command(args, target, sessions, client_flags, json_path):
    """The load generator's command line: the same session parameters for both."""
    common = ["--target", target, "--sessions", str(sessions), "--duration", str(args.duration),
              "--rate", args.rate, "--particles", str(args.particles), "--ramp", str(args.ramp),
              "--encoding", args.encoding] + client_flags + args.generator_arg
    if args.generator == "cpp":
        return [args.loadgen] + common + ["--threads", str(args.threads), "--json", json_path]
    return ["/usr/bin/python3", args.loadtest] + common + ["--processes", str(args.processes)]


def generator_result(args, out, json_path):
    """The generator's result, in one shape: loadtest.py's RESULT line (errors and rejections
    as tallies) or localizer-loadgen's JSON (errors and rejected as counts)."""
    if args.generator == "cpp":
        if not os.path.exists(json_path):
            sys.stderr.write(out.stdout + out.stderr)
            raise RuntimeError("localizer-loadgen wrote no result")
        with open(json_path) as f:
            r = json.load(f)
        os.unlink(json_path)
        return {"blocks_per_s": r["blocks_per_s"], "blocks_sent": r["blocks_sent"], "latency_ms": r["latency_ms"],
                "errors": r["errors"], "rejections": r["rejected"], "wall_s": r["wall_s"],
                "run_us_per_block": r["generator_cpu_us_per_block"]}  # its own figure: the run only
    result_line = [l for l in out.stdout.splitlines() if l.startswith("RESULT ")]
    if not result_line:
        sys.stderr.write(out.stdout + out.stderr)
        raise RuntimeError("loadtest printed no RESULT line")
    r = json.loads(result_line[0][len("RESULT "):])
    return {"blocks_per_s": r["blocks_per_s"], "blocks_sent": r["blocks_sent"], "latency_ms": r["latency_ms"],
            "errors": sum(r["errors"].values()), "rejections": sum(r["rejections"].values()),
            "wall_s": r["wall_s"], "run_us_per_block": None}


def thread_switches(pid):
    """{tid: (name, voluntary, involuntary)} context switches of every thread of `pid` now
    (/proc/<pid>/task/*/status; /proc/<pid>/status alone counts the main thread only)."""
    out = {}
    for tid in os.listdir(f"/proc/{pid}/task"):
        try:
            with open(f"/proc/{pid}/task/{tid}/status") as f:
                text = f.read()
        except OSError:
            continue  # the thread ended meanwhile
        name = re.search(r"^Name:\s*(.*)$", text, re.M).group(1)
        vol = int(re.search(r"^voluntary_ctxt_switches:\s*(\d+)", text, re.M).group(1))
        invol = int(re.search(r"^nonvoluntary_ctxt_switches:\s*(\d+)", text, re.M).group(1))
        out[tid] = (name, vol, invol)
    return out


def switches_between(before, after):
    """Context switches between two thread_switches() snapshots: (voluntary, involuntary,
    {thread name: voluntary}). Threads that ended in between are not counted (gRPC's and
    ours live as long as the server)."""
    vol = invol = 0
    by_name = {}
    for tid, (name, v, i) in after.items():
        _, v0, i0 = before.get(tid, (name, 0, 0))
        vol += v - v0
        invol += i - i0
        by_name[name] = by_name.get(name, 0) + (v - v0)
    return vol, invol, by_name


def children_cpu_s():
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime


def run_row(args, sessions, mode="plain"):
    server_flags, client_flags = security_flags(mode, args.pki)
    proc, ports = start_server(args.server, args.bare, args.workers, args.server_arg + server_flags)
    no_metrics = {"engine_cpu_s": 0.0, "blocks": 0.0}
    json_path = tempfile.mktemp(prefix="localizer-loadgen-", suffix=".json")
    try:
        cmd = generator_command(args, f"127.0.0.1:{ports['grpc_port']}", sessions, client_flags, json_path)
        gen0 = children_cpu_s()  # the server is not waited for yet: only the generator counts
        gen = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        if args.warmup > 0:  # the server's figures from here on; the generator's stay whole-run
            time.sleep(args.warmup)
        before = scrape(ports["metrics_port"]) if not args.bare else no_metrics
        cpu0 = process_cpu_s(proc.pid)
        flt0 = process_minor_faults(proc.pid)
        sw0 = thread_switches(proc.pid)
        t0 = time.time()
        stdout, stderr = gen.communicate()
        out = subprocess.CompletedProcess(cmd, gen.returncode, stdout, stderr)
        window_s = time.time() - t0
        gen_cpu = children_cpu_s() - gen0
        cpu1 = process_cpu_s(proc.pid)
        flt1 = process_minor_faults(proc.pid)
        sw1 = thread_switches(proc.pid)
        after = scrape(ports["metrics_port"]) if not args.bare else no_metrics
    finally:
        proc.send_signal(signal.SIGTERM)
        proc.wait(timeout=30)
    result = generator_result(args, out, json_path)
    if args.bare and args.warmup > 0:  # no metrics: the window's share of the blocks sent
        blocks = max(1.0, result["blocks_sent"] * window_s / result["wall_s"])
    else:
        blocks = max(1.0, after["blocks"] - before["blocks"] if not args.bare else result["blocks_sent"])
    server_cpu = cpu1 - cpu0
    engine_cpu = after["engine_cpu_s"] - before["engine_cpu_s"]
    vol, invol, by_name = switches_between(sw0, sw1)
    return {
        "sessions": sessions, "security": mode, "generator": args.generator,
        "blocks_per_s": result["blocks_per_s"],
        "p50_ms": result["latency_ms"]["p50"], "p95_ms": result["latency_ms"]["p95"],
        "p99_ms": result["latency_ms"]["p99"],
        "errors": result["errors"], "rejections": result["rejections"],
        "server_cpu_cores": server_cpu / (window_s if args.warmup > 0 else result["wall_s"]),
        "server_us_per_block": 1e6 * server_cpu / blocks,
        "engine_us_per_block": 1e6 * engine_cpu / blocks,
        "outside_engine_us_per_block": 1e6 * (server_cpu - engine_cpu) / blocks,
        "generator_cpu_cores": gen_cpu / result["wall_s"],
        "generator_us_per_block": 1e6 * gen_cpu / max(1, result["blocks_sent"]),  # start-up included
        "generator_run_us_per_block": result["run_us_per_block"],
        # The server's wake-ups: voluntary context switches (a thread blocked and was woken)
        # and involuntary ones (preempted), per block, over the generator's run.
        "server_vcs_per_block": vol / blocks, "server_ivcs_per_block": invol / blocks,
        # Heap growth: minor page faults per block (0 once the server's memory stops growing).
        "server_minflt_per_block": (flt1 - flt0) / blocks, "warmup_s": args.warmup,
        "server_vcs_per_block_by_thread": {k: round(v / blocks, 3) for k, v in sorted(by_name.items()) if v},
    }


def main():
    here = os.path.dirname(os.path.abspath(__file__))
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--build", default=os.path.join(here, "..", "..", "build"), help="build directory")
    p.add_argument("--sessions", default="100,200,300", help="comma-separated session counts, one row each")
    p.add_argument("--duration", type=float, default=20.0, help="seconds of streaming per row")
    p.add_argument("--ramp", type=float, default=2.0, help="seconds over which sessions start")
    p.add_argument("--warmup", type=float, default=0.0,
                   help="seconds of the generator's run before the server's figures (CPU, switches, faults per "
                        "block) start counting; 0: the whole run (each session's resume history of 256 estimates "
                        "takes ~12 s of real-time blocks to fill, the live view's 600 points ~28 s)")
    p.add_argument("--rate", choices=["realtime", "max"], default="realtime")
    p.add_argument("--particles", type=int, default=4096)
    p.add_argument("--encoding", choices=["float", "pcm16"], default="float")
    p.add_argument("--generator", choices=["python", "cpp"], default="python",
                   help="load generator: python (clients/python/loadtest.py) or cpp (localizer-loadgen)")
    p.add_argument("--processes", type=int, default=1, help="load-generator processes (python)")
    p.add_argument("--threads", type=int, default=1, help="load-generator pacing threads (cpp)")
    p.add_argument("--workers", type=int, default=0, help="server --workers (0: one per core)")
    p.add_argument("--server-arg", action="append", default=[], help="extra localizer-server flag (repeatable)")
    p.add_argument("--generator-arg", action="append", default=[],
                   help="extra load-generator flag (repeatable), e.g. --generator-arg=--hop=4096")
    p.add_argument("--server", default=None,
                   help="localizer-server binary (default: <build>/server/localizer-server); to set two builds "
                        "side by side")
    p.add_argument("--bare", action="store_true", help="drive bare_stream_server (gRPC alone) instead")
    p.add_argument("--security", default="plain",
                   help="comma-separated modes, each row run once per mode: plain, tls, mtls-token")
    args = p.parse_args()
    if args.warmup > 0 and args.warmup >= args.duration:
        p.error("--warmup must be shorter than --duration")
    modes = args.security.split(",")
    for mode in modes:
        if mode not in ("plain", "tls", "mtls-token"):
            p.error(f"--security: unknown mode {mode!r} (plain, tls, mtls-token)")
    if args.bare and modes != ["plain"]:
        p.error("--security needs the real server (not --bare)")
    args.pki = None
    if modes != ["plain"]:
        args.pki = tempfile.mkdtemp(prefix="localizer-bench-pki-")
        subprocess.run(["bash", os.path.join(here, "..", "..", "deploy", "tls", "make_test_certs.sh"), args.pki],
                       check=True, capture_output=True)
    if args.server is None:
        args.server = (os.path.join(args.build, "tests", "bench", "bare_stream_server") if args.bare
                       else os.path.join(args.build, "server", "localizer-server"))
    args.loadtest = os.path.join(args.build, "clients", "python", "loadtest.py")
    args.loadgen = os.path.join(args.build, "clients", "localizer-loadgen")
    print(f"# {args.rate}, {args.duration:g} s per row, {args.particles} particles, 4 ch 44.1 kHz, "
          f"4096-sample blocks and frames, hop 2048, {args.encoding}; {os.cpu_count()} CPUs (load generator included); "
          f"generator {args.generator}")
    print("sessions  security    blocks/s  p50_ms  p95_ms  p99_ms  errors  rejected  server_cores  us/block  engine_us  "
          "outside_us  gen_cores  gen_us/block  vcs/block  ivcs/block  minflt/block")
    for n in [int(s) for s in args.sessions.split(",")]:
        for mode in modes:
            r = run_row(args, n, mode)
            print(f"{r['sessions']:8d}  {mode:10s}  {r['blocks_per_s']:8.1f}  {r['p50_ms']:6.1f}  {r['p95_ms']:6.1f}  "
                  f"{r['p99_ms']:6.1f}  {r['errors']:6d}  {r['rejections']:8d}  {r['server_cpu_cores']:12.2f}  "
                  f"{r['server_us_per_block']:8.0f}  {r['engine_us_per_block']:9.0f}  "
                  f"{r['outside_engine_us_per_block']:10.0f}  {r['generator_cpu_cores']:9.2f}  "
                  f"{r['generator_us_per_block']:12.0f}  {r['server_vcs_per_block']:9.2f}  "
                  f"{r['server_ivcs_per_block']:10.2f}  {r['server_minflt_per_block']:12.2f}", flush=True)
            print("RESULT " + json.dumps(r), file=sys.stderr)


if __name__ == "__main__":
    main()
