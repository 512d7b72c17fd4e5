#!/usr/bin/python3
"""eval_doa_csv.py EST.csv TRUTH.csv: a localizer direction session's CSV (one row per frame and
source) against the truth seen from the array centre. Per frame the source with the highest
power (as ODAS's eval takes the most active track) is scored; also frames with a source, ids
seen, and source-frames beyond 20 degrees of the truth (false-source time)."""
import csv
import math
import sys

import numpy as np

rows = list(csv.DictReader(open(sys.argv[1])))
truth = list(csv.DictReader(open(sys.argv[2])))
tt = np.array([float(r["t_s"]) for r in truth])
tp = np.array([[float(r[k]) for k in ("x_m", "y_m", "z_m")] for r in truth])
frames = {}
for r in rows:
    frames.setdefault(int(r["frame"]), []).append(r)
err, ids, far, t_last = [], set(), 0, 0.0
for f, rs in sorted(frames.items()):
    t = float(rs[0]["t_s"])
    t_last = t
    u = np.array([np.interp(t, tt, tp[:, i]) for i in range(3)])
    u /= np.linalg.norm(u)
    best, best_p = None, -math.inf
    for r in rs:
        if not r["source_id"]:
            continue
        az, el = float(r["azimuth_rad"]), float(r["elevation_rad"])
        d = np.array([math.cos(el) * math.cos(az), math.cos(el) * math.sin(az), math.sin(el)])
        if math.degrees(math.acos(min(1.0, max(-1.0, d @ u)))) > 20.0:
            far += 1
        p = float(r["power_db"]) if r["power_db"] else -math.inf
        if best is None or p > best_p:
            best, best_p = (d, r["source_id"]), p
    if best is not None:
        ids.add(best[1])
        err.append(math.degrees(math.acos(min(1.0, max(-1.0, best[0] @ u)))))
hop_s = t_last / max(1, len(frames) - 1)
print("ours: frames %d, with a source %d (%.0f%%), direction error median %.1f deg p90 %.1f deg, ids scored %d, "
      "source-frames > 20 deg off %d (%.1f s per minute)"
      % (len(frames), len(err), 100.0 * len(err) / max(1, len(frames)), np.median(err), np.percentile(err, 90),
         len(ids), far, far * hop_s * 60.0 / max(t_last, 1e-9)))
