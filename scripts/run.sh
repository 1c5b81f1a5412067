#!/usr/bin/env bash
# The main job: installs the dependencies, builds, and runs the headless job on the default device
# (a GPU with ray tracing pipelines if present, else lavapipe). Output lands in ./out.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
bash scripts/build.sh
mkdir -p out
./build/samples/bench/raybridge-bench --quick --scenario all --out out/bench.json "$@"
