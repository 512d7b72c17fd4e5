#!/usr/bin/env bash
# The main job, from a fresh Debian 12 machine: install what is missing, build, simulate a
# scenario, track it, print a few estimates and the error against the truth.
# Usage: deploy/demo.sh [SCENARIO] (default tetra-water; `localizer-cli simulate --list`)
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
scenario="${1:-tetra-water}"
"$root/deploy/install.sh"
"$root/deploy/build.sh"
cli="${LOCALIZER_BUILD_DIR:-$root/build}/clients/localizer-cli"
out="$root/build/demo/$scenario"
"$cli" simulate --scenario "$scenario" --out "$out" --seed 1
"$cli" track --array "$out/array.json" --wav "$out/signals.wav" --out "$out/estimates.csv" --seed 1 --print-every 10
"$cli" score --truth "$out/truth.csv" --estimates "$out/estimates.csv"
