#!/usr/bin/env bash
# Reflections' sun visibility from the shadow image (docs/performance.md, "Reflections: sun visibility from the shadow
# image"): `ultra` at 2560x1440 along the glossy scene's path and the perf fly-through, the candidate off
# (--no-sun-cache: shadows traced as in `on`, the reflection pass given no image) and on, the raw-rate probe first.
# Off runs before and after on (off, off2: the run-to-run spread); on and off2 are scored against off's final images
# (--compare-with). Only the stats.json files, the log and the environment come back, in $OUT/sun_cache.tar.gz. On
# the GPU machine (device tool, carry .devcarry):
#   bash scripts/gpu/sun_cache_ab.sh        (RB_AB_SIZE, RB_AB_FRAMES, RB_AB_SCENES="glossy perf" for a rehearsal)
set -uo pipefail
cd "$(dirname "$0")/../.."
declare -A SCENE_ARGS=(
  [perf]="--perf-scene --models-from @SCENES@ --camera-path scripts/gpu/perf_flythrough.json"
  [glossy]="--glossy-scene --camera-path scripts/gpu/glossy_path.json"
)
variants=()
for scene in ${RB_AB_SCENES:-glossy perf}; do
  args="${SCENE_ARGS[$scene]} --preset ultra"
  variants+=("${scene}_off|$args --no-sun-cache" "${scene}_on|$args --compare-with @RDIR@/${scene}_off"
             "${scene}_off2|$args --no-sun-cache --compare-with @RDIR@/${scene}_off")
done
joined="$(IFS=';'; echo "${variants[*]}")"
OUT="${OUT:-$PWD/out/gpu}"
RB_RENDER_SIZE="${RB_AB_SIZE:-2560 1440}" RB_RENDER_FRAMES="${RB_AB_FRAMES:-240}" RB_RENDER_LIMIT=110 RB_RENDER_PROBE=1 \
  RB_TIME_BUDGET="${RB_TIME_BUDGET:-560}" RB_RENDER_VARIANTS="$joined" OUT="$OUT" bash scripts/gpu/run_remote.sh render
rc=$?
# The archive holds every render's final.png too (megabytes each at 2560x1440): keep what the numbers need.
keep="$(mktemp -d)"
tar -C "$keep" -xzf "$OUT/render_gpu.tar.gz" && rm -f "$OUT/render_gpu.tar.gz"
(cd "$keep" && find . \( -name stats.json -o -name '*.log' -o -name env.txt \) -print0 |
  tar --null -czf "$OUT/sun_cache.tar.gz" -T -)
ls -la "$OUT"
exit $rc
