#!/usr/bin/python3
"""Scores `localizer-cli track` on a room scene made by `localizer-cli simulate --room`.

The scene folder holds sources.csv (each talker's azimuth, elevation and cone angle from the
array's centroid) and sounding.csv (when each talker sounds). Per frame of the track CSV, a
row is *heard* when its source_present is 1 (the track took a peak this frame, or its session
holds it present through a short gap); a talker's
sounding frame is covered when a heard row lies within the tolerance of the talker (azimuth,
or the cone angle for a line array; ACCURACY.md, "Named room scenes through the CLI").

Per talker: its sounding frames, the share covered by a heard row, the share with any
reported row (heard or coasting) within the tolerance, the same heard share over the frames in
which no other talker sounds (alone), the identities that were heard on it
in at least 5 frames, and the median error of its heard rows. Then false time: heard rows
farther than the tolerance from every talker, in seconds per minute of audio; and lingering
time: heard rows within the tolerance of talkers that are all silent (more than 0.1 s after
their last stop), which the false time does not count.

usage: /usr/bin/python3 room_scene_score.py SCENE_DIR TRACK_CSV [--tolerance-deg 15] [--line]
(--line: score cone angles; the default is azimuths)
"""
import argparse
import collections
import csv
import math


# A talker's direction may still be heard this long after it stops (its frame, 32 ms at the
# direction sessions' default, and the room's first reflections) before a present row there
# counts as lingering.
LINGER_GRACE_S = 0.1


def separation(a, b, line=False):
    """Angle between two azimuths (wrapped), or between two cone angles for a line (rad)."""
    if line:
        return abs(a - b)
    return abs((a - b + math.pi) % (2 * math.pi) - math.pi)


def score(scene_dir, track_csv, line=False, tolerance_deg=15.0):
    """The scores as a dict: 'talkers' (per talker: sounding, heard, reported, ids, errors_deg)
    and 'false_s_per_min'."""
    with open(f'{scene_dir}/sources.csv') as f:
        talkers = list(csv.DictReader(f))
    sounding = collections.defaultdict(list)
    with open(f'{scene_dir}/sounding.csv') as f:
        for r in csv.DictReader(f):
            sounding[int(r['source'])].append((float(r['on_s']), float(r['off_s'])))
    with open(track_csv) as f:
        rows = list(csv.DictReader(f))

    key = 'cone_angle_rad' if line else 'azimuth_rad'

    frames = sorted({float(r['t_s']) for r in rows})
    if len(frames) < 2:
        raise SystemExit('the track CSV holds fewer than two frames')
    hop_s = frames[1] - frames[0]
    minutes = (frames[-1] - frames[0] + hop_s) / 60.0
    by_frame = collections.defaultdict(list)
    for r in rows:
        if r['source_id'] and r[key] != '':
            by_frame[float(r['t_s'])].append(r)
    tolerance = math.radians(tolerance_deg)

    result = {'talkers': []}
    for k, talker in enumerate(talkers):
        truth = float(talker[key])
        frames_on = [t for t in frames if any(a <= t <= b for a, b in sounding[k])]
        heard = reported = alone = heard_alone = 0
        ids = collections.Counter()
        errors = []
        for t in frames_on:
            near = [r for r in by_frame[t] if separation(float(r[key]), truth, line) < tolerance]
            took = [r for r in near if r['source_present'] == '1']
            heard += bool(took)
            reported += bool(near)
            if not any(any(a <= t <= b for a, b in sounding[j]) for j in sounding if j != k):
                alone += 1
                heard_alone += bool(took)
            for r in took:
                ids[r['source_id']] += 1
                errors.append(math.degrees(separation(float(r[key]), truth, line)))
        steady = sorted((i for i, c in ids.items() if c >= 5), key=lambda i: -ids[i])
        result['talkers'].append({'sounding': len(frames_on), 'heard': heard, 'reported': reported,
                                  'alone': alone, 'heard_alone': heard_alone, 'ids': steady,
                                  'errors_deg': sorted(errors)})

    false_rows = lingering_rows = 0
    for t in frames:
        for r in by_frame[t]:
            if r['source_present'] != '1':
                continue
            near = [k for k, s in enumerate(talkers) if separation(float(r[key]), float(s[key]), line) < tolerance]
            if not near:
                false_rows += 1
            elif not any(a <= t <= b + LINGER_GRACE_S for k in near for a, b in sounding[k]):
                lingering_rows += 1
    result['false_rows'] = false_rows
    result['false_s_per_min'] = false_rows * hop_s / minutes
    # Present where a talker is but while it is silent (past LINGER_GRACE_S after it stopped):
    # not counted as false above, since a row within the tolerance is that talker's.
    result['lingering_rows'] = lingering_rows
    result['lingering_s_per_min'] = lingering_rows * hop_s / minutes
    return result


def main():
    parser = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    parser.add_argument('scene_dir', help='folder written by localizer-cli simulate --room')
    parser.add_argument('track_csv', help='CSV written by localizer-cli track on that scene')
    parser.add_argument('--tolerance-deg', type=float, default=15.0,
                        help='a row this close to a talker is that talker (default: 15 degrees)')
    parser.add_argument('--line', action='store_true', help='a line array: score cone angles')
    args = parser.parse_args()
    result = score(args.scene_dir, args.track_csv, args.line, args.tolerance_deg)
    for k, t in enumerate(result['talkers']):
        n = max(1, t['sounding'])
        errors = t['errors_deg']
        median = f'{errors[len(errors) // 2]:.1f}' if errors else '-'
        alone = f'{100 * t["heard_alone"] / t["alone"]:.0f} %' if t['alone'] else '-'
        print(f'talker {k}: sounding frames {t["sounding"]}, heard {100 * t["heard"] / n:.0f} %, '
              f'alone {t["alone"]} frames, heard {alone} of them, reported {100 * t["reported"] / n:.0f} %, ids {len(t["ids"])} {t["ids"]}, median error {median} deg')
    print(f'false: {result["false_rows"]} heard rows beyond {args.tolerance_deg:g} deg of every talker, '
          f'{result["false_s_per_min"]:.1f} s per minute')
    print(f'lingering: {result["lingering_rows"]} heard rows near talkers that are all silent, '
          f'{result["lingering_s_per_min"]:.1f} s per minute')


if __name__ == '__main__':
    main()
