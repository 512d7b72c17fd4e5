#!/usr/bin/env bash
# Direction finding side by side (issue 18; BENCHMARKS.md "Direction sessions beside ODAS"):
# ODAS (introlab/odas: SRP-PHAT + Kalman, 16 kHz, its shipped ReSpeaker 4-mic config and
# 256/128 framing) and localizer's direction sessions on the exact planar ReSpeaker geometry,
# on the same 60 s of audio (one source circling the board, ../shared/tools/odas-bench's
# gen_audio.py), CPU by its cputime.py, each case pinned to core 1, best of 3 interleaved.
# Then each tool's direction error against the truth (eval_tracks.py for ODAS,
# eval_doa_csv.py for ours).
#
# usage: tests/bench/odas_doa.sh ODAS_GIT_DIR [WORK_DIR] [BUILD_DIR]
#   ODAS_GIT_DIR  bare git dir of introlab/odas (the search tool's fetch of github:introlab/odas)
#   WORK_DIR      default /tmp/odas-doa (ODAS is built there, never in the repository)
#   BUILD_DIR     our build (default build/)
# ODAS needs libconfig-dev libpulse-dev libasound2-dev (measurement only; not the project's).
set -euo pipefail
ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)
[ $# -ge 1 ] || { sed -n 2,15p "$0"; exit 2; }
ODAS_GIT=$(cd "$1" && pwd); W=${2:-/tmp/odas-doa}; B=${3:-$ROOT/build}
H=$ROOT/../shared/tools/odas-bench; PY=/usr/bin/python3
CLI=$B/clients/localizer-cli
mkdir -p $W/odas/src $W/cfg $W/out $W/logs
: > $W/raw.tsv
if [ ! -x $W/odas/build/bin/odaslive ]; then
  git --git-dir=$ODAS_GIT archive HEAD | tar -x -C $W/odas/src
  cmake -S $W/odas/src -B $W/odas/build -DCMAKE_BUILD_TYPE=Release -DODAS_DISABLE_INSTALL=ON \
    -DCMAKE_POLICY_VERSION_MINIMUM=3.5 -DCMAKE_C_FLAGS_RELEASE="-O3 -DNDEBUG" > $W/logs/odas_cmake.log 2>&1
  make -C $W/odas/build -j2 odaslive > $W/logs/odas_make.log 2>&1
  gcc -O2 -shared -fPIC -o $W/odas/libnoclock.so $H/noclock.c
fi
git --git-dir=$ODAS_GIT log -1 --format='ODAS %H (%ad)' --date=short
$PY $H/gen_audio.py --fs 16000 --duration 60 --out $W/data > $W/logs/gen.log
# the exact (planar) geometry, sources above the board
$PY - "$W/data" <<'PYEOF'
import json, sys
d = sys.argv[1]
a = json.load(open(d + '/array_16000.json'))
for s in a['sensors_m']: s[2] = 0.0
a['source_side'] = {'normal': [0, 0, 1]}
a.pop('band_hz', None)
json.dump(a, open(d + '/planar_16000.json', 'w'), indent=1)
PYEOF
$PY $H/make_cfg.py --base $W/odas/src/config/odaslive/respeaker_4_mic_array.cfg --raw $W/data/mics_16000.raw \
  --fs-raw 16000 --raw-hop 128 --fs 16000 --frame 256 --hop 128 --mode kalman --tracked $W/out/odas-k16.json \
  --out $W/cfg/odas-k16.cfg
ODASRUN="env LD_PRELOAD=$W/odas/libnoclock.so $W/odas/build/bin/odaslive -s -c $W/cfg/odas-k16.cfg"
ours() { echo "$CLI track --array $W/data/planar_16000.json --wav $W/data/mics_16000.wav --print-every 0 --out $W/out/$1.csv ${@:2}"; }
declare -A CMD=(
  [odas-k16]="$ODASRUN"
  [ours-512-k4]="$(ours ours-512-k4 --frame 512 --hop 256)"
  [ours-512-k1]="$(ours ours-512-k1 --frame 512 --hop 256 --max-sources 1)"
  [ours-256-k4]="$(ours ours-256-k4 --frame 256 --hop 128)"
  [ours-256-k1]="$(ours ours-256-k1 --frame 256 --hop 128 --max-sources 1)"
)
for rep in 1 2 3; do
  for id in odas-k16 ours-512-k4 ours-512-k1 ours-256-k4 ours-256-k1; do
    $PY $H/cputime.py $W/cpu.txt taskset -c 1 ${CMD[$id]} >>$W/logs/$id.out 2>>$W/logs/$id.err
    echo -e "$id\t$rep\t$(cat $W/cpu.txt)" | tee -a $W/raw.tsv
  done
done
$PY - "$W/raw.tsv" <<'PYEOF'
import sys
best = {}
for line in open(sys.argv[1]):
    case, rep, cpu = line.rstrip('\n').split('\t')
    u, s = map(float, cpu.split())
    best[case] = min(best.get(case, 1e9), u + s)
for case, t in sorted(best.items()):
    print("%-14s best of 3: %.3f s CPU for 60 s -> %.2f ms per audio-second" % (case, t, t / 60 * 1000))
PYEOF
$PY $H/eval_tracks.py odas $W/out/odas-k16.json $W/data/truth_16000.csv 128 16000
for c in ours-512-k4 ours-512-k1 ours-256-k4 ours-256-k1; do
  echo -n "$c: "; $PY $ROOT/tests/bench/eval_doa_csv.py $W/out/$c.csv $W/data/truth_16000.csv
done
