#!/usr/bin/env bash
# The main job, from a fresh Debian 12 machine: install what is missing, build, start
# localizer-server on loopback, stream a simulated scenario through it in real time with
# localizer-cli, print the estimates with their error and the latency figures, show the
# server's /metrics, and stop the server cleanly (SIGTERM, graceful drain).
# Usage: deploy/demo.sh [SCENARIO [DURATION_S]]   (default tetra-water 10)
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
scenario="${1:-tetra-water}"
duration="${2:-10}"
"$root/deploy/install.sh"
# Only what the demo runs: the two binaries and the engine under them (211 build steps on a
# fresh configure instead of 486; the tests come with deploy/test.sh).
build_start_ns=$(date +%s%N)
"$root/deploy/build.sh" --target localizer-server --target localizer-cli
echo "== build step (localizer-server, localizer-cli) took" \
  "$(awk -v ns=$(( $(date +%s%N) - build_start_ns )) 'BEGIN { printf "%.1f", ns / 1e9 }') s"
build="${LOCALIZER_BUILD_DIR:-$root/build}"
cli="$build/clients/localizer-cli"
server="$build/server/localizer-server"
out="$build/demo/$scenario"
mkdir -p "$out"

ready="$out/server.ready"
rm -f "$ready"
echo "== starting localizer-server on loopback (log: $out/server.log)"
"$server" --listen 127.0.0.1:0 --metrics-listen 127.0.0.1:0 --ready-file "$ready" 2> "$out/server.log" &
server_pid=$!
trap 'kill -TERM $server_pid 2> /dev/null || true' EXIT
for _ in $(seq 1 100); do [ -s "$ready" ] && break; sleep 0.1; done
[ -s "$ready" ] || { echo "server did not start; see $out/server.log" >&2; exit 1; }
grpc_port=$(sed -E 's/.*"grpc_port": ([0-9]+).*/\1/' "$ready")
metrics_port=$(sed -E 's/.*"metrics_port": ([0-9]+).*/\1/' "$ready")
echo "   gRPC 127.0.0.1:$grpc_port, metrics http://127.0.0.1:$metrics_port/metrics"

echo "== streaming scenario $scenario ($duration s of audio, real time) through the server"
"$cli" simulate --scenario "$scenario" --duration "$duration" --seed 1 --server "127.0.0.1:$grpc_port" \
  --rate realtime --print-every 10 --out "$out"

echo "== a few lines of http://127.0.0.1:$metrics_port/metrics"
"$root/deploy/http_get.py" "http://127.0.0.1:$metrics_port/metrics" | \
  grep -E '^localizer_(stage_seconds_(sum|count)|estimates_total|blocks_total|sessions_closed)' | grep -v 'backend="gpu"' || true

echo "== stopping the server (SIGTERM: drain, then exit)"
kill -TERM "$server_pid"
wait "$server_pid"
trap - EXIT
tail -n 3 "$out/server.log"
