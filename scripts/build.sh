#!/usr/bin/env bash
# Configures and builds Raybridge (Release, Ninja) into ./build. Extra arguments go to cmake's configure step.
set -euo pipefail
cd "$(dirname "$0")/.."
jobs=$(nproc 2>/dev/null || echo 2)
cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release -DRAYBRIDGE_BUILD_TESTS=ON "$@"
cmake --build build -j "$jobs"
