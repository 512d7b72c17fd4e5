#!/usr/bin/python3
"""Random room scenes through `localizer-cli simulate --room` and `track`, scored per scene.

The nine named scenes (scenes/rooms) are what the direction tracker was tuned on; this draws
scenes it was not: per scene a seeded room (4-8 x 3.5-7 x 2.5-3.5 m, RT60 0.2-0.6 s), the
array somewhere in it (at least 1 m from the walls), 1 to --max-talkers talkers 1-3 m away
(at least --min-separation-deg apart as the array sees them: azimuths, or cone angles for a
line), the first at level 0 and the others 0 to -10 dB, white bursts with pauses (or with
--signal speech the speech-like talker of engine/sim/speech_like.h), sensor noise
-15 dB against a level-0 talker at 1 m. Each scene is rendered, tracked with `track`'s
defaults (plus --track-arg) and scored by room_scene_score.score (a talker's sounding frame
is heard when a row within 15 degrees has source_present 1).

Prints one line per scene, then the pooled heard share, the median per-talker heard share,
the false time (heard rows beyond 15 degrees of every talker), the lingering time (heard rows
near talkers that are all silent) and the identities per talker.

usage: /usr/bin/python3 room_scene_campaign.py --array scenes/arrays/square4.json
           [--scenes 20] [--seed 1] [--line] [--max-talkers 3] [--snr-db LO HI] [--signal speech] [--cli build/clients/localizer-cli]
           [--work DIR] [--track-arg=--flag=value ...] [--json out.json]
"""
import argparse
import json
import math
import os
import random
import statistics
import subprocess
import sys
import tempfile
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import room_scene_score  # noqa: E402

NOISE_DB = -15  # sensor noise against a level-0 talker's direct sound at 1 m


def draw_scene(rng, sensors, line, max_talkers, min_separation_rad, snr_db=None, signal='bursts'):
    """A scene dict for simulate --room, and each talker's scored angle (for the record)."""
    size = [rng.uniform(4.0, 8.0), rng.uniform(3.5, 7.0), rng.uniform(2.5, 3.5)]
    rt60 = rng.uniform(0.2, 0.6)
    reach = max(math.dist(s, [0.0, 0.0, 0.0]) for s in sensors)  # the array's extent from its origin
    array = [rng.uniform(1.0 + reach, size[0] - 1.0 - reach), rng.uniform(1.0 + reach, size[1] - 1.0 - reach),
             rng.uniform(0.8, 1.2)]
    centroid = [array[k] + sum(s[k] for s in sensors) / len(sensors) for k in range(3)]
    axis = None
    if line:
        a, b = sensors[0], sensors[-1]
        d = [b[k] - a[k] for k in range(3)]
        n = math.sqrt(sum(v * v for v in d))
        axis = [v / n for v in d]

    def angle_of(p):
        v = [p[k] - centroid[k] for k in range(3)]
        if line:
            return math.acos(max(-1.0, min(1.0, sum(v[k] * axis[k] for k in range(3)) / math.sqrt(sum(x * x for x in v)))))
        return math.atan2(v[1], v[0])

    talkers, angles = [], []
    count = rng.randint(1, max_talkers)
    for k in range(count):
        for _ in range(1000):
            azimuth = rng.uniform(-math.pi, math.pi)
            distance = rng.uniform(1.0, 3.0)
            p = [centroid[0] + distance * math.cos(azimuth), centroid[1] + distance * math.sin(azimuth),
                 centroid[2] + rng.uniform(-0.2, 0.6)]
            if not all(0.3 <= p[i] <= size[i] - 0.3 for i in range(3)):
                continue
            angle = angle_of(p)
            if all(room_scene_score.separation(angle, other, line) >= min_separation_rad for other in angles):
                break
        else:
            break  # no room for another talker in this scene
        angles.append(angle)
        if snr_db:
            # Direct sound at distance r: level - 20 log10(r) over noise at NOISE_DB (1 m).
            level = rng.uniform(*snr_db) + NOISE_DB + 20.0 * math.log10(math.dist(p, centroid))
        else:
            level = 0.0 if k == 0 else rng.uniform(-10.0, 0.0)
        talkers.append({'position_m': [round(v, 3) for v in p], 'signal': signal, 'level_db': round(level, 1)})
    scene = {'room': {'size_m': [round(v, 3) for v in size], 'rt60_s': round(rt60, 3)},
             'array_position_m': [round(v, 3) for v in array], 'sample_rate_hz': 16000, 'duration_s': 20,
             'noise_db': NOISE_DB, 'sources': talkers}
    return scene, angles


def finish(process):
    if process.returncode != 0:
        raise SystemExit(f'{" ".join(process.args)} failed ({process.returncode}):\n{process.stderr}')


def main():
    parser = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    parser.add_argument('--array', required=True, help='array file (e.g. scenes/arrays/square4.json)')
    parser.add_argument('--scenes', type=int, default=20, help='scenes to draw (default 20)')
    parser.add_argument('--seed', type=int, default=1, help='campaign seed (default 1): scene i uses seed*1000+i')
    parser.add_argument('--line', action='store_true', help='a line array: separate and score cone angles')
    parser.add_argument('--max-talkers', type=int, default=3, help='1 to this many talkers per scene (default 3)')
    parser.add_argument('--min-separation-deg', type=float, default=30.0,
                        help='talkers at least this far apart as the array sees them (default 30)')
    parser.add_argument('--snr-db', type=float, nargs=2, metavar=('LO', 'HI'),
                        help="each talker's direct sound LO to HI dB over the sensor noise at the array "
                             '(default: levels 0 to -10 dB against a noise of -15 dB at 1 m)')
    parser.add_argument('--signal', choices=['bursts', 'speech'], default='bursts',
                        help="the talkers' signal (simulate --room: white bursts, or speech-like; default bursts)")
    parser.add_argument('--cli', default='build/clients/localizer-cli', help='the localizer-cli to run')
    parser.add_argument('--work', help='folder for the scenes (default: a temporary one, removed)')
    parser.add_argument('--track-arg', action='append', default=[], help='extra flag for track (repeatable)')
    parser.add_argument('--json', help='write every scene and its scores here')
    args = parser.parse_args()
    if not 1 <= args.scenes <= 1000:
        parser.error('--scenes must be in [1, 1000]')
    if not 1 <= args.max_talkers <= 6:
        parser.error('--max-talkers must be in [1, 6]')
    if args.snr_db and not -20.0 <= args.snr_db[0] <= args.snr_db[1] <= 40.0:
        parser.error('--snr-db needs -20 <= LO <= HI <= 40')
    with open(args.array) as f:
        sensors = json.load(f)['sensors_m']

    temporary = None if args.work else tempfile.TemporaryDirectory(prefix='room_campaign_')
    work = args.work or temporary.name
    records = []
    started = time.monotonic()
    for i in range(args.scenes):
        rng = random.Random(args.seed * 1000 + i)
        scene, angles = draw_scene(rng, sensors, args.line, args.max_talkers, math.radians(args.min_separation_deg),
                                   args.snr_db, args.signal)
        folder = os.path.join(work, f'scene{i:03d}')
        os.makedirs(folder, exist_ok=True)
        with open(os.path.join(folder, 'scene.json'), 'w') as f:
            json.dump(scene, f, indent=1)
        run = [args.cli, 'simulate', '--room', os.path.join(folder, 'scene.json'), '--array', args.array,
               '--out', folder, '--seed', str(args.seed * 1000 + i)]
        finish(subprocess.run(run, capture_output=True, text=True))
        run = [args.cli, 'track', '--array', os.path.join(folder, 'array.json'), '--wav',
               os.path.join(folder, 'signals.wav'), '--out', os.path.join(folder, 'track.csv'), '--print-every', '0']
        finish(subprocess.run(run + args.track_arg, capture_output=True, text=True))
        result = room_scene_score.score(folder, os.path.join(folder, 'track.csv'), args.line)
        shares = [t['heard'] / max(1, t['sounding']) for t in result['talkers']]
        records.append({'scene': scene, 'scores': result, 'heard_shares': shares})
        print(f'[{i + 1}/{args.scenes}, {time.monotonic() - started:.0f} s] scene {i}: '
              f'{len(shares)} talker(s), RT60 {scene["room"]["rt60_s"]:.2f} s, heard '
              + ' / '.join(f'{100 * s:.0f} %' for s in shares)
              + f', ids ' + ' / '.join(str(len(t['ids'])) for t in result['talkers'])
              + f', false {result["false_s_per_min"]:.1f} s/min', flush=True)

    talkers = [t for r in records for t in r['scores']['talkers']]
    pooled = sum(t['heard'] for t in talkers) / max(1, sum(t['sounding'] for t in talkers))
    shares = [s for r in records for s in r['heard_shares']]
    false = [r['scores']['false_s_per_min'] for r in records]
    lingering = [r['scores']['lingering_s_per_min'] for r in records]
    errors = sorted(e for t in talkers for e in t['errors_deg'])
    alone = sum(t['alone'] for t in talkers)
    heard_alone = sum(t['heard_alone'] for t in talkers)
    overlapped = sum(t['sounding'] for t in talkers) - alone
    print(f'{len(records)} scenes, {len(talkers)} talkers: heard {100 * pooled:.1f} % of sounding talker-frames '
          f'(alone {100 * heard_alone / max(1, alone):.1f} % of {alone}, with another talker '
          f'{100 * (sum(t["heard"] for t in talkers) - heard_alone) / max(1, overlapped):.1f} % of {overlapped}; '
          f'median talker {100 * statistics.median(shares):.0f} %, talkers under 95 %: '
          f'{sum(s < 0.95 for s in shares)}); false {statistics.mean(false):.2f} s/min mean, '
          f'{statistics.median(false):.2f} median, scenes over 1 s/min: {sum(f > 1.0 for f in false)}; '
          f'lingering {statistics.mean(lingering):.2f} s/min mean; '
          f'ids per talker {statistics.mean(len(t["ids"]) for t in talkers):.2f}; median error of heard rows '
          + (f'{errors[len(errors) // 2]:.1f} deg' if errors else '-'))
    if args.json:
        with open(args.json, 'w') as f:
            json.dump(records, f)
    if temporary:
        temporary.cleanup()


if __name__ == '__main__':
    main()
