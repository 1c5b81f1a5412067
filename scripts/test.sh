#!/usr/bin/env bash
# Installs the dependencies, builds everything and runs the whole test suite on the default device
# (lavapipe where there is no GPU) with the Vulkan validation layer on; any validation error fails a test.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
bash scripts/build.sh
export RAYBRIDGE_VALIDATION=1
ctest --test-dir build --output-on-failure --timeout 1800 -j 2
