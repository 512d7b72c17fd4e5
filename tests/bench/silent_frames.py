#!/usr/bin/python3
"""silent_frames.py CAMPAIGN CAMPAIGN.json [CAMPAIGN.json ...]: what the silent-failure
frames of scene_campaign runs look like. Every scene with any silent time (silent_failure_s > 0
in the JSON) is replayed with `scene_campaign --trace` and each of its frames that counts as
silent (initialised, present, not ambiguous, error > 10 x the per-frame CRLB, position NEES > 50)
is put in one class by what the tracker saw on it:
  no pairs     the update used no pair (the track coasted)
  < 3 pairs    1-2 pairs: the frame cannot fix a position by itself
  NIS high     >= 3 pairs and NIS / pairs > 3: the innovations said something was wrong
  consistent   >= 3 pairs and NIS / pairs <= 3: the track explained the data while wrong
counted separately for 4-sensor arrays (three pairs, no redundancy) and larger ones.
CAMPAIGN is the scene_campaign binary that wrote the JSON (e.g. build/tests/bench/scene_campaign).
Prints how many scenes and frames, and the table."""
import collections
import json
import subprocess
import sys


def silent_frames(trace_text):
    lines = trace_text.splitlines()
    sensors = int(lines[0].split(" sensors")[0].split()[-1])
    out = []
    for line in lines[3:]:
        x = line.split()
        if len(x) < 15 or x[0] == "scene" or not x[1].isdigit():
            continue
        try:
            init, present, ambiguous = int(x[1]), int(x[2]), int(x[3])
            err_over_crlb, nees, pairs, nis = float(x[9]), float(x[12]), int(x[13]), float(x[14])
        except ValueError:  # "-" where the frame has no estimate
            continue
        if init and present and not ambiguous and err_over_crlb > 10 and nees > 50:
            if pairs == 0:
                kind = "no pairs"
            elif pairs < 3:
                kind = "< 3 pairs"
            else:
                kind = "NIS high" if nis / pairs > 3 else "consistent"
            out.append((sensors == 4, kind))
    return out


def main(argv):
    if len(argv) < 3 or argv[1] in ("-h", "--help"):
        print(__doc__)
        return 0 if len(argv) > 1 and argv[1] in ("-h", "--help") else 2
    campaign = argv[1]
    table = collections.Counter()
    scenes = 0
    for path in argv[2:]:
        for row in json.load(open(path))["scenes"]:
            if not row.get("silent_failure_s"):
                continue
            scenes += 1
            trace = subprocess.run([campaign, "--trace", str(row["seed"])], capture_output=True, text=True,
                                   check=True).stdout
            table.update(silent_frames(trace))
    print(f"scenes with silent time: {scenes}; silent frames: {sum(table.values())}")
    for four in (True, False):
        cells = ", ".join(f"{kind} {table[(four, kind)]}" for kind in ("no pairs", "< 3 pairs", "NIS high", "consistent"))
        print(f"  {'4 sensors' if four else '5+ sensors'}: {cells}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
