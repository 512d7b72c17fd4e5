#!/usr/bin/env bash
# Installs the Debian 12 packages localizer needs to build, test and run.
# Idempotent: when everything is present it only checks (well under a second); it runs
# `apt-get update` only when something is missing. Needs root (or sudo) to install.
set -euo pipefail

packages=(
  build-essential cmake pkg-config git
  libeigen3-dev          # linear algebra (engine/)
  libfftw3-dev           # GCC-PHAT FFTs, float and double (engine/tdoa)
  libsndfile1-dev        # WAV in and out, int16/24/32 and float32 (clients/)
  nlohmann-json3-dev     # array.json (clients/)
  libgtest-dev libgmock-dev libbenchmark-dev  # tests and benchmarks
  libgrpc++-dev protobuf-compiler-grpc libprotobuf-dev protobuf-compiler  # service (server/, proto/)
  libcivetweb-dev        # /metrics HTTP endpoint (server/)
  libyaml-cpp-dev        # the XAV deployment's localization YAML (clients/io/xav_config.h)
  libasound2-dev         # live capture from ALSA devices, track --alsa (clients/io/alsa_capture.h);
                         # optional at configure time: without it the flag says so
  libssl-dev             # SHA-256 and constant-time compare of tokens, TLS file checks (server/service),
                         # HTTPS on the HTTP side (server/metrics/tls_front)
  openssl                # test certificates (deploy/tls/make_test_certs.sh, tests/server/security_test,
                         # tls_front_test, metrics_https_test)
  python3-grpcio python3-grpc-tools python3-numpy  # Python client and load test (clients/)
  python3-protobuf python3-soundfile  # the package localizer: messages; localizer.audio (WAV, FLAC)
  python3-pip python3-venv python3-setuptools python3-wheel  # pip install ./clients/python, offline
                         # (--no-build-isolation), and its test (tests/python/test_package_install)
  pybind11-dev python3-pybind11 python3-dev  # localizer.engine, the in-process engine bindings
                         # of the Python package (clients/python/engine_module)
  python3-scipy          # Nolan's alpha-stable quantile table (tests/sim/alpha_stable_test)
  prometheus             # promtool, and a real Prometheus server in the ops tests (deploy/prometheus)
  python3-yaml           # the ops tests read the shipped YAML (deploy/prometheus, deploy/k8s)
  nginx-light            # the session-affine front in the scale-out test (deploy/nginx)
  chromium               # headless, draws the live view in its test (tests/ops)
)

missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -eq 0 ]; then
  echo "install.sh: all ${#packages[@]} packages present"
  exit 0
fi

echo "install.sh: installing ${missing[*]}"
sudo_cmd=()
[ "$(id -u)" -eq 0 ] || sudo_cmd=(sudo)
export DEBIAN_FRONTEND=noninteractive
"${sudo_cmd[@]}" apt-get update -qq
"${sudo_cmd[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}"
