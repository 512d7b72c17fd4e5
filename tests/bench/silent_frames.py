#!/usr/bin/python3
"""silent_frames.py CAMPAIGN CAMPAIGN.json [CAMPAIGN.json ...]: what the silent-failure
frames of scene_campaign runs look like. Every scene with any silent time (silent_failure_s > 0
in the JSON) is replayed with `scene_campaign --trace`, and each frame the trace marks silent
(the campaign's own rule: counted, initialised, not ambiguous, error > 10 x the per-frame CRLB,
position NEES > 50) is put in one class by what the tracker saw on it:
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
        # t_s init pres amb far silent range r_err error crlb err/crlb brg/crlb sd nees pairs nis ...
        x = line.split()
        if len(x) < 16 or "." not in x[0] or x[5] != "1":  # not a frame (the summary row), or not silent
            continue
        pairs, nis = int(x[14]), float(x[15])
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
