"""The load test's report: merges per-process snapshots, prints the progress line each
second and the final summary with its machine-readable RESULT line (see loadtest.py)."""
import collections
import json
import sys
import time

import numpy as np


class Aggregator:
    """Merges the snapshots of all processes; prints the progress line and the summary."""

    def __init__(self, args, n_workers, t0):
        self.args, self.t0 = args, t0
        self.latest = [None] * n_workers
        self.window = []
        self.finals = [None] * n_workers

    def update(self, w, snap):
        self.latest[w] = snap
        self.window.append(snap["window"])

    def total(self, key, snaps):
        return sum(s[key] for s in snaps if s is not None)

    def progress(self):
        snaps = [s for s in self.latest if s is not None]
        window = np.concatenate(self.window) if self.window else np.array([])
        self.window = []
        p99 = f"{1e3 * np.percentile(window, 99):.1f} ms" if window.size else "-"
        lag = max((s["loop_lag_s"] for s in snaps), default=0.0)
        rej = self.total_counter("rejections", snaps)
        err = self.total_counter("errors", snaps)
        print(f"[{time.monotonic() - self.t0:6.1f} s] open {self.total('open', snaps)}/"
              f"{self.args.sessions}  blocks {self.total('blocks', snaps)}  estimates "
              f"{self.total('estimates', snaps)}  p99 {p99}  rejections {sum(rej.values())}  "
              f"errors {sum(err.values())}  client-loop-lag {1e3 * lag:.0f} ms",
              file=sys.stderr, flush=True)

    @staticmethod
    def total_counter(key, snaps):
        c = collections.Counter()
        for s in snaps:
            c.update(s[key])
        return c

    def result(self, wall_s):
        a, snaps = self.args, self.finals
        lat = np.concatenate([s["latencies"] for s in snaps]) * 1e3
        blocks, estimates = self.total("blocks", snaps), self.total("estimates", snaps)
        firsts = [s["first_send"] for s in snaps if s["first_send"] is not None]
        lasts = [s["last_send"] for s in snaps if s["last_send"] is not None]
        last_est = [s["last_estimate"] for s in snaps if s["last_estimate"] is not None]
        send_s = (max(lasts) - min(firsts)) if firsts else 0.0
        est_s = (max(last_est) - min(firsts)) if last_est else 0.0
        pct = (lambda q: round(float(np.percentile(lat, q)), 3)) if lat.size else (lambda q: None)
        return {
            "target": a.target, "sessions": a.sessions, "sessions_opened": self.total("opened", snaps),
            "rate": a.rate, "encoding": a.encoding, "channels": a.channels,
            "sample_rate_hz": a.sample_rate, "block_samples": a.block, "frame_samples": a.frame,
            "hop_samples": a.hop, "particles": a.particles, "processes": a.processes,
            "backends": dict(self.total_counter("backends", snaps)),
            "duration_s": a.duration, "ramp_s": a.ramp, "wall_s": round(wall_s, 3),
            "interrupted": any(s["interrupted"] for s in snaps),
            "blocks_sent": blocks, "blocks_per_s": round(blocks / send_s, 2) if send_s > 0 else None,
            "estimates": estimates,
            "estimates_per_s": round(estimates / est_s, 2) if est_s > 0 else None,
            "latency_ms": {"p50": pct(50), "p95": pct(95), "p99": pct(99),
                           "max": round(float(lat.max()), 3) if lat.size else None},
            "max_behind_schedule_ms": round(1e3 * max(s["behind_max_s"] for s in snaps), 3),
            "rejections": dict(self.total_counter("rejections", snaps)),
            "errors": dict(self.total_counter("errors", snaps)),
            "gaps": self.total("gaps", snaps),
        }


def print_summary(r):
    def counts(d):
        return "  ".join(f"{k}={v}" for k, v in sorted(d.items())) or "none"
    lat = r["latency_ms"]
    fmt = (lambda v: "-" if v is None else f"{v:.1f}")
    print(f"sessions            {r['sessions']} ({r['sessions_opened']} opened, backends "
          f"{counts(r['backends'])}, {r['processes']} process(es))")
    print(f"duration            {r['duration_s']:g} s streaming per session, ramp {r['ramp_s']:g} s, "
          f"wall {r['wall_s']:.1f} s ({r['rate']}, {r['encoding']})"
          f"{', INTERRUPTED' if r['interrupted'] else ''}")
    print(f"blocks sent         {r['blocks_sent']} ({fmt(r['blocks_per_s'])} /s; "
          f"max behind schedule {r['max_behind_schedule_ms']:.1f} ms)")
    print(f"estimates received  {r['estimates']} ({fmt(r['estimates_per_s'])} /s)")
    print(f"latency ms          p50 {fmt(lat['p50'])}  p95 {fmt(lat['p95'])}  "
          f"p99 {fmt(lat['p99'])}  max {fmt(lat['max'])}")
    print(f"rejections          {counts(r['rejections'])}")
    print(f"errors              {counts(r['errors'])}")
    print(f"gaps                {r['gaps']}")
    print("RESULT " + json.dumps(r, sort_keys=True), flush=True)
