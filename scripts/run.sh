#!/usr/bin/env bash
# The main job: installs the dependencies, builds, and renders the procedural demo scene headless with
# Raybridge's ray-traced effects on the default device (a GPU with ray tracing pipelines if there is one,
# else lavapipe on the CPU). Writes out/final.png and out/final.exr; arguments go to raybridge-render
# (e.g. --dump, --preset ultra, --mode raster, --scene FILE.gltf).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
bash scripts/build.sh
./build/tools/render/raybridge-render "$@"
