#!/usr/bin/python3
"""Open a Track session, stream 3 s of a synthetic source in real time, print the estimates
(numpy blocks in, localizer.Estimate dataclasses out).

    /usr/bin/python3 build/clients/python/track_example.py 127.0.0.1:50051 \
        [--tls-ca ca.crt --tls-cert client.crt --tls-key client.key --auth-token-file token]
"""
import argparse
import threading
import time

import localizer as lc
from localizer import synth

parser = argparse.ArgumentParser(description="stream 3 s of a synthetic source, print the estimates")
parser.add_argument("target", nargs="?", default="127.0.0.1:50051", help="server address HOST:PORT")
lc.add_connect_arguments(parser)
args = parser.parse_args()
target = args.target
fs, block = 44100.0, 4096
sensors = synth.tetrahedron(edge_m=1.5)                   # 4 hydrophones, 1.5 m apart
source, tdoa = synth.source_with_integer_tdoas(sensors, (2.5, 1.5, -1.0), 1500.0, fs)
audio = synth.broadband_at_sensors(tdoa, int(3 * fs), fs)  # (4, samples) float32

channel = lc.connect(target, **lc.connect_kwargs(args))
config = lc.session_config(sensors, fs, sound_speed_mps=1500.0, band_hz=(200, 8000),
                           seed=1, label="track-example")
session = lc.TrackSession.open(channel, config)  # raises grpc.RpcError if refused
print(f"session {session.session_id} on {session.opened.backend}; source at "
      f"({source[0]:.2f}, {source[1]:.2f}, {source[2]:.2f}) m")


def stream():
    for k, start in enumerate(range(0, audio.shape[1] - block + 1, block)):
        time.sleep(max(0.0, k * block / fs - (time.monotonic() - t0)))  # real time
        session.send(audio[:, start:start + block])
    session.close()  # half-close: the server sends the last estimates and ends the stream


t0 = time.monotonic()
threading.Thread(target=stream, daemon=True).start()
for e in session.estimates():
    where = (f"({e.position_m[0]:6.2f}, {e.position_m[1]:6.2f}, {e.position_m[2]:6.2f}) m"
             f" +- {max(e.position_sd_m):.2f} m" if e.initialised else "waiting for a fix")
    print(f"frame {e.frame_index:3d}  t {e.t_s:6.3f} s  {where}")
for r in session.rejected:
    print(f"rejected block {r.sequence}: {r.code} {r.message}")
