#!/usr/bin/env bash
# Configures and builds the native library, CLI and tests (Release, -O2) into build/. Arguments are
# passed to the configuration (e.g. -DQGP_BPY_TESTS=ON).
set -euo pipefail
cd "$(dirname "$0")/.."
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release "$@" >/dev/null
cmake --build build -j"$(nproc)"
echo "build: build/bin/qgp, build/lib/libqgp.so"
