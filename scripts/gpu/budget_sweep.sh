#!/usr/bin/env bash
# The frame budget's sweep (docs/performance.md, "Frame budget"): `ultra` at 2560x1440 along the perf fly-through and
# the glossy scene's path, unbudgeted and under --budget 2, 3, 4 and 6 ms, each budgeted run scored against the
# unbudgeted one's final images (--compare-with); the glossy scene's `reflections` and `high` for the reflection
# pass's rate; the raw-rate probe first. On the GPU machine (device tool, carry .devcarry):
#   bash scripts/gpu/budget_sweep.sh            (RB_SWEEP_SCENES="perf glossy demo" picks scenes)
set -euo pipefail
cd "$(dirname "$0")/../.."
declare -A SCENE_ARGS=(
  [perf]="--perf-scene --models-from @SCENES@ --camera-path scripts/gpu/perf_flythrough.json"
  [glossy]="--glossy-scene --camera-path scripts/gpu/glossy_path.json"
  [demo]="--characters 3 --models-from @SCENES@ --fps 30 --time 8"
)
variants=()
for scene in ${RB_SWEEP_SCENES:-perf glossy}; do
  args="${SCENE_ARGS[$scene]}"
  variants+=("${scene}_ultra|$args --preset ultra")
  for ms in ${RB_SWEEP_BUDGETS:-2 3 4 6}; do
    variants+=("${scene}_b$ms|$args --preset ultra --budget $ms --compare-with @RDIR@/${scene}_ultra")
  done
  if [ "$scene" = glossy ]; then
    variants+=("glossy_reflections|$args --preset reflections" "glossy_high|$args --preset high")
  fi
done
joined="$(IFS=';'; echo "${variants[*]}")"
RB_RENDER_SIZE="2560 1440" RB_RENDER_FRAMES="${RB_SWEEP_FRAMES:-240}" RB_RENDER_LIMIT=80 RB_RENDER_PROBE=1 \
  RB_TIME_BUDGET="${RB_TIME_BUDGET:-570}" RB_RENDER_VARIANTS="$joined" bash scripts/gpu/run_remote.sh render
