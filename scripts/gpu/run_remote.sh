#!/usr/bin/env bash
# Runs the benchmark and the tests on the GPU machine (NVIDIA, no Vulkan loader, no network) from the folder
# .devcarry/ that scripts/gpu/prepare.sh assembled and the device tool carried. Run from the repository root:
#
#   bash scripts/gpu/run_remote.sh [all|MODE[,MODE...]]   MODE: bench, tests, inject, render, effects, animated,
#                                                          lights, perf, adaptive, soak (default all; inject,
#                                                          the failure-injection cases, tlas, the TLAS
#                                                          benchmarks alone (with the tlas-motion runs of
#                                                          earlier builds carried as bin/raybridge-bench-X),
#                                                          trace, the primary-ray rate against the probe, and
#                                                          motion, the motion benchmark at 2560x1440, run only
#                                                          when named)
#
# Results go to $OUT (the device tool brings that folder back, at most 8 files): bench_gpu.json, bench_gpu.log,
# tests_gpu.log, effects_gpu.json, effects_gpu.log, render_gpu.tar.gz (render logs, stats.json and final.png
# of each render, env.txt), summary.txt. Every step's exit code is recorded; the script exits non-zero if any step failed.
# The whole run stays under RB_TIME_BUDGET seconds (default 500, inside the tool's 10-minute command limit):
# a step that would start after the budget is skipped and counted as failed.
#
# Environment:
#   OUT=DIR             where results go (set by the device tool; default ./out/gpu)
#   RB_DRY_RUN=1        local rehearsal: no dpkg -x into /, no ldconfig, no VK_DRIVER_FILES (uses this machine's
#                       loader and drivers, e.g. lavapipe). Also implied when not running as root.
#   RB_BENCH_ARGS=...   benchmark arguments (default: --scenario all --full)
#   RB_TIME_BUDGET=500  seconds for the whole run
#   RB_PERF_SIZE="2560 1440", RB_PERF_FRAMES=40, RB_PERF_PATH_FRAMES=240, RB_PERF_PRESETS="hard-shadows low medium
#   high ultra", RB_PERF_VARIANT_PRESETS="hard-shadows low ultra", RB_PERF_BENCH_ARGS=--full: the perf mode's
#   size, frames per row and along the path, presets (of the current build and of the earlier ones) and benchmark
#   arguments (smaller ones for a rehearsal on lavapipe); RB_PERF_EXTRAS=0 leaves out the raster, ray-traced,
#   classifier and fly-through rows (the presets and their earlier builds only)
#   RB_PERF_PATH_VARIANTS=1: the earlier builds' hybrid rows along the fly-through too; RB_PERF_BENCHES=0 leaves
#   out the perf mode's TLAS and trace benchmarks
#   RB_RUNTIME_DIR=DIR  where .devcarry is unpacked (default /tmp/raybridge-devcarry)
#   RB_TESTS="NAME ..." the tests mode runs only these executables (tests.txt names); RB_TEST_ARGS="[tag]" gives
#                       them these arguments instead of their own
set -u

MODE="${1:-all}"
for m in ${MODE//,/ }; do
  case "$m" in all|bench|tests|inject|render|effects|animated|lights|perf|adaptive|soak|tlas|trace|motion) ;; *) echo "usage: $0 [all|MODE[,MODE...]] with MODE bench, tests, inject, render, effects, animated, lights, perf, adaptive, soak, tlas, trace or motion" >&2; exit 2 ;; esac
done
want() { [ "$MODE" = all ] || [[ ",$MODE," == *",$1,"* ]]; }
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
cd "$ROOT"
CARRY="$ROOT/.devcarry"
OUT="${OUT:-$ROOT/out/gpu}"
RT="${RB_RUNTIME_DIR:-/tmp/raybridge-devcarry}"
BUDGET="${RB_TIME_BUDGET:-500}"
NVIDIA_ICD=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json
DRY="${RB_DRY_RUN:-0}"
if [ "$(id -u)" != 0 ] && [ "$DRY" != 1 ]; then
  echo "[gpu] not root: dry run (no dpkg -x into /, no ldconfig)"
  DRY=1
fi
mkdir -p "$OUT"
SUMMARY="$OUT/summary.txt"
: >"$SUMMARY"
STEPS=()
FAILED=0

say() { echo "[gpu] $*"; }
record() {  # NAME RC SECONDS
  STEPS+=("$(printf '%-28s rc=%-4s %6ss' "$1" "$2" "$3")")
  [ "$2" = 0 ] || [ "$2" = all-skipped ] || FAILED=$((FAILED + 1))
}
left() { echo $((BUDGET - SECONDS)); }
# step NAME TIMEOUT LOG CMD...: runs CMD with a timeout no longer than what is left of the budget, appending to LOG.
step() {
  local name="$1" limit="$2" logfile="$3"
  shift 3
  local remaining
  remaining=$(left)
  if [ "$remaining" -lt 20 ]; then
    say "skipping $name: the time budget is spent"
    echo "== $name: skipped (time budget spent)" >>"$logfile"
    record "$name" skipped 0
    return
  fi
  [ "$limit" -gt "$((remaining - 10))" ] && limit=$((remaining - 10))
  say "running $name (limit ${limit}s)"
  echo "== $name: $*" >>"$logfile"
  local t0=$SECONDS rc
  timeout --kill-after=10 "$limit" "$@" >>"$logfile" 2>&1
  rc=$?
  [ "$rc" = 124 ] && echo "== $name: timed out after ${limit}s" >>"$logfile"
  echo "== $name: exit code $rc after $((SECONDS - t0))s" >>"$logfile"
  # Catch2's 4: every test case skipped itself (the preset hashes on another driver than theirs): not a failure.
  if [ "$rc" = 4 ] && tail -n 4 "$logfile" | grep -Eq 'test cases: +[0-9]+ \| +[0-9]+ skipped'; then rc=all-skipped; fi
  record "$name" "$rc" "$((SECONDS - t0))"
}
finish() {
  {
    echo "raybridge GPU run: mode $MODE, $(date -u +%Y-%m-%dT%H:%M:%SZ), ${SECONDS}s, dry run $DRY"
    printf '%s\n' "${STEPS[@]}"
    echo "failed steps: $FAILED"
  } | tee "$SUMMARY"
  [ "$FAILED" = 0 ]
  exit $?
}

# ---- unpack the carried folder -----------------------------------------------------------------------------
[ -d "$CARRY/bin" ] || { say "no .devcarry/bin: run scripts/gpu/prepare.sh here first and carry .devcarry"; record carry 1 0; finish; }
rm -rf "$RT"
cp -r "$CARRY" "$RT"
find "$RT" -type f -name '*.gz' -exec gunzip -f {} +
chmod +x "$RT"/bin/* 2>/dev/null
say "unpacked .devcarry into $RT ($(du -sh "$RT" | cut -f1))"

# ---- Vulkan loader and driver ------------------------------------------------------------------------------
t0=$SECONDS
if [ "$DRY" = 1 ]; then
  say "dry run: using this machine's Vulkan loader and drivers"
  record loader 0 0
else
  rc=0
  for deb in "$RT"/debs/*.deb; do dpkg -x "$deb" / || rc=$?; done
  ldconfig || rc=$?
  ldconfig -p | grep -q 'libvulkan.so.1 ' || { say "libvulkan.so.1 is still missing after dpkg -x"; rc=1; }
  record loader "$rc" $((SECONDS - t0))
  if [ -f "$NVIDIA_ICD" ]; then
    export VK_DRIVER_FILES="$NVIDIA_ICD"
  else
    say "warning: $NVIDIA_ICD not found; leaving the driver choice to the loader"
  fi
fi
LIBPATH="$RT/lib"
# The carried libstdc++ only when the machine's own lacks the newest symbol version the binaries use.
need_cxx="$(cat "$RT/lib-fallback/GLIBCXX_NEEDED" 2>/dev/null)"
sys_cxx="$(ldconfig -p | awk '/libstdc\+\+\.so\.6 .*x86-64/ { print $NF; exit }')"
if [ -n "$need_cxx" ] && { [ -z "$sys_cxx" ] || ! grep -aq "$need_cxx" "$sys_cxx"; }; then
  say "the system libstdc++ (${sys_cxx:-none}) lacks $need_cxx: using the carried one"
  LIBPATH="$LIBPATH:$RT/lib-fallback"
fi
need_c="$(cat "$RT/lib-fallback/GLIBC_NEEDED" 2>/dev/null)"
sys_c="$(ldconfig -p | awk '/libc\.so\.6 .*x86-64/ { print $NF; exit }')"
if [ -n "$need_c" ] && [ -n "$sys_c" ] && ! grep -aq "$need_c" "$sys_c"; then
  say "warning: the system glibc ($sys_c) lacks $need_c; the binaries will not start (build on an older glibc)"
fi
export LD_LIBRARY_PATH="$LIBPATH${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}"
export VK_LAYER_PATH="$RT/layers"
export RAYBRIDGE_RENDER="$RT/bin/raybridge-render"  # the tools' tests run the carried render command
export RAYBRIDGE_MINIMAL_INTEGRATION="$RT/bin/minimal_integration"  # and the carried minimal integration
# NVIDIA's ICD needs a static TLS block; dlopen'ed after Embree/TBB (the tests) it finds none left, so the
# driver's TLS library is loaded at start-up instead.
for tls in /usr/local/nvidia/lib64/libnvidia-tls.so.* /usr/lib/x86_64-linux-gnu/libnvidia-tls.so.*; do
  if [ -e "$tls" ]; then
    export LD_PRELOAD="$tls${LD_PRELOAD:+:$LD_PRELOAD}"
    break
  fi
done

# Tests look for glTF models at <source dir compiled in>/../shared/scenes; point that path at the carried copy.
SRC_DIR="$(cat "$RT/source_dir.txt" 2>/dev/null || echo "")"
SCENES="$RT/data/scenes"
if [ -n "$SRC_DIR" ] && [ -d "$SCENES" ] && [ ! -e "$SRC_DIR/../shared/scenes" ]; then
  if [ "$DRY" = 1 ]; then
    say "dry run: not creating $SRC_DIR/../shared/scenes"
  else
    mkdir -p "$SRC_DIR/../shared" && ln -s "$SCENES" "$SRC_DIR/../shared/scenes" && say "linked $SRC_DIR/../shared/scenes"
  fi
fi

{
  echo "date: $(date -u +%Y-%m-%dT%H:%M:%SZ)"
  echo "host: $(uname -a)"
  echo "dry run: $DRY"
  echo "VK_DRIVER_FILES=${VK_DRIVER_FILES:-}"
  echo "VK_LAYER_PATH=$VK_LAYER_PATH"
  echo "LD_LIBRARY_PATH=$LD_LIBRARY_PATH"
  command -v nvidia-smi >/dev/null && nvidia-smi --query-gpu=name,driver_version,memory.total --format=csv
  ldconfig -p | grep libvulkan
  cat "$RT/manifest.txt" 2>/dev/null | head -n 4
  echo "ldd raybridge-bench:"
  ldd "$RT/bin/raybridge-bench"
} >"$OUT/env.txt" 2>&1

# ---- benchmark (full sizes, validation off) ----------------------------------------------------------------
if want bench; then
  read -r -a BENCH_ARGS <<<"${RB_BENCH_ARGS:---scenario all --full}"
  : >"$OUT/bench_gpu.log"
  RAYBRIDGE_VALIDATION=0 step bench 300 "$OUT/bench_gpu.log" \
    "$RT/bin/raybridge-bench" "${BENCH_ARGS[@]}" --scenes "$SCENES" --out "$OUT/bench_gpu.json"
  grep -E '^raybridge-bench on|^total' "$OUT/bench_gpu.log"
fi

# ---- render command: frame times raster vs hybrid at 1920x1080 (validation off) -------------------------------
if want render; then
  : >"$OUT/render_gpu.log"
  # RB_RENDER_BIN=NAME: another render command of bin/ (an earlier build, or a wrapper such as raybridge-render-noconv).
  RENDER="$RT/bin/${RB_RENDER_BIN:-raybridge-render}"
  RDIR="$(mktemp -d)"
  # RB_RENDER_VARIANTS="name|args;name|args" replaces the variants below (e.g. an A/B of one switch, alternated);
  # RB_RENDER_SIZE="W H" the size (default 1920 1080); RB_RENDER_FRAMES the frames of each (default 12);
  # RB_RENDER_LIMIT the seconds each may take (default 60). In a variant's args @RDIR@ is the folder the variants
  # write to (--compare-with @RDIR@/NAME scores against an earlier variant) and @SCENES@ the carried models.
  VARIANTS=("raster|--mode raster" "hybrid|--mode hybrid" "raster_ultra|--mode raster --preset ultra"
            "hybrid_ultra|--mode hybrid --preset ultra" "hybrid_low|--mode hybrid --preset low")
  [ -n "${RB_RENDER_VARIANTS:-}" ] && IFS=';' read -r -a VARIANTS <<<"$RB_RENDER_VARIANTS"
  read -r RW RH <<<"${RB_RENDER_SIZE:-1920 1080}"
  # RB_RENDER_PROBE=1: the raw-rate probe first (stress and primary rates, ~1M triangles), into render_gpu.log.
  if [ "${RB_RENDER_PROBE:-0}" = 1 ] && [ -x "$RT/probe/probe" ]; then
    RAYBRIDGE_VALIDATION=0 step "probe k10" 60 "$OUT/render_gpu.log" "$RT/probe/probe" --width "$RW" --height "$RH" \
      --rays 64 --k 10 --ground-tiles 64 --reps 7
  fi
  for variant in "${VARIANTS[@]}"; do
    name="${variant%%|*}"
    vline="${variant#*|}"
    vline="${vline//@RDIR@/$RDIR}"
    read -r -a vargs <<<"${vline//@SCENES@/$SCENES}"
    RAYBRIDGE_VALIDATION=0 step "render $name" "${RB_RENDER_LIMIT:-60}" "$OUT/render_gpu.log" \
      "$RENDER" --width "$RW" --height "$RH" --frames "${RB_RENDER_FRAMES:-12}" --dump "${vargs[@]}" \
      --out "$RDIR/$name"
  done
  grep -E 'engine GPU ms|Raybridge:' "$OUT/render_gpu.log"
  # One archive with the render outputs, its log and the environment: the tool brings back at most 8 files.
  cp "$OUT/render_gpu.log" "$OUT/env.txt" "$RDIR/" && rm -f "$OUT/render_gpu.log" "$OUT/env.txt"
  tar -C "$RDIR" -czf "$OUT/render_gpu.tar.gz" --exclude='*.exr' . 2>/dev/null
fi

# ---- effects: speed against error at 1920x1080 (validation off), FLIP computed here ------------------------
if want effects; then
  : >"$OUT/effects_gpu.log"
  EIMG="$(mktemp -d)"
  RAW=()
  [ -f "$OUT/bench_gpu.json" ] && RAW=(--raw-rate-json "$OUT/bench_gpu.json")
  # RB_EFFECTS_ONLY=LIST: those effects alone (raybridge-effects-bench --effects LIST), e.g. reflections.
  ONLY=()
  [ -n "${RB_EFFECTS_ONLY:-}" ] && ONLY=(--effects "$RB_EFFECTS_ONLY")
  RAYBRIDGE_VALIDATION=0 step effects 240 "$OUT/effects_gpu.log" "$RT/bin/raybridge-effects-bench" \
    --width 1920 --height 1080 "${RAW[@]}" "${ONLY[@]}" --images "$EIMG" --out "$OUT/effects_gpu.json"
  # FLIP needs the 1080p images, too large to bring back: computed on the machine from the carried wheel.
  if ls "$ROOT"/.whl/flip_evaluator-*.whl >/dev/null 2>&1; then
    python3 -m pip install -q --no-index --no-deps --no-compile --target /tmp/flipsite "$ROOT"/.whl/flip_evaluator-*.whl \
      >>"$OUT/effects_gpu.log" 2>&1
    PYTHONPATH=/tmp/flipsite step flip 150 "$OUT/effects_gpu.log" python3 "$ROOT/scripts/plot_speed_vs_error.py" \
      "$OUT/effects_gpu.json" --images "$EIMG" --flip-into "$OUT/effects_gpu.json" --no-plots
  fi
  grep -E '^(shadows|ao|reflections):' "$OUT/effects_gpu.log" | grep -v reference | head -n 60
fi

# ---- animated: K skinned characters, sync vs async BLAS work, 2560x1440 (validation off); the raw-rate probe in
# the same run; then the two-queue SDK tests and the animated smoke run with validation (sync validation) on.
if want animated; then
  : >"$OUT/animated_gpu.log"
  if [ -x "$RT/probe/probe" ]; then
    RAYBRIDGE_VALIDATION=0 step probe 60 "$OUT/animated_gpu.log" "$RT/probe/probe" --width 2560 --height 1440 \
      --rays 64 --k 10 --ground-tiles 64 --reps 7
  fi
  RAYBRIDGE_VALIDATION=0 step animated 330 "$OUT/animated_gpu.log" "$RT/bin/raybridge-animated-bench" \
    ${RB_ANIMATED_ARGS:-} --scenes "$SCENES" --out "$OUT/animated_gpu.json"
  RAYBRIDGE_VALIDATION=1 step "async tests" 120 "$OUT/animated_gpu.log" "$RT/bin/raybridge_tests" "[async],[dynamic]"
  RAYBRIDGE_VALIDATION=1 step "animated smoke" 120 "$OUT/animated_gpu.log" "$RT/bin/raybridge-animated-bench" \
    --quick --validation --scenes "$SCENES" --out "$(mktemp -d)/animated_smoke.json"
  grep -E '^\| |^device|stress|All tests passed|test cases|FAILED|SKIPPED|validation' "$OUT/animated_gpu.log" | head -n 80
fi

# ---- lights: the many-light benchmark at 2560x1440 with the raw-rate probe in the same run, then the demo scene's
# punctual lights at 2560x1440 (times: raster with shadow maps, exact, 1 and 4 rays) and at 640x360 (lights.png
# pictures of the same variants). Validation off.
if want lights; then
  : >"$OUT/lights_gpu.log"
  if [ -x "$RT/probe/probe" ]; then
    RAYBRIDGE_VALIDATION=0 step probe 60 "$OUT/lights_gpu.log" "$RT/probe/probe" --width 2560 --height 1440 \
      --rays 64 --k 10 --ground-tiles 64 --reps 7
  fi
  RAYBRIDGE_VALIDATION=0 step "lights bench" 240 "$OUT/lights_gpu.log" "$RT/bin/raybridge-bench" --scenario lights \
    ${RB_LIGHTS_ARGS:-} --out "$OUT/lights_bench_gpu.json"
  LDIR="$(mktemp -d)"
  for size in "2560 1440" "640 360"; do
    read -r lw lh <<<"$size"
    for variant in "raster|--mode raster --preset hard-shadows" "exact|--effects lights --light-rays 0" \
                   "rays1|--effects lights --light-rays 1" "rays4|--effects lights --light-rays 4"; do
      name="${variant%%|*}_${lw}"
      read -r -a vargs <<<"${variant#*|}"
      RAYBRIDGE_VALIDATION=0 step "lights $name" 60 "$OUT/lights_gpu.log" \
        "$RT/bin/raybridge-render" --width "$lw" --height "$lh" --frames 16 --dump "${vargs[@]}" --out "$LDIR/$name"
    done
  done
  grep -E '^\| |stress|engine GPU ms|Raybridge:' "$OUT/lights_gpu.log" | head -n 80
  tar -C "$LDIR" -czf "$OUT/lights_render_gpu.tar.gz" --exclude='*.exr' . 2>/dev/null
fi
# ---- perf: docs/performance.md. The probe on ~100k and ~1M triangles, then the performance scene (--perf-scene,
# ~3M triangles) and the demo scene at 2560x1440 per preset (hybrid; raster for low and ultra), the fly-through
# along scripts/gpu/perf_flythrough.json (raster and hybrid), the TLAS and trace benchmarks; perf_report.py writes
# perf_gpu.json. With bin/raybridge-render-VARIANT (earlier builds carried by prepare.sh's EXTRA_BINS), the hybrid
# rows of RB_PERF_VARIANT_PRESETS are rendered by each of them too, right after the current one, as the "before"
# rows of docs/performance.md (scene name SCENE-VARIANT). Validation off.
if want perf; then
  : >"$OUT/perf_gpu.log"
  PDIR="$(mktemp -d)"
  PFRAMES="${RB_PERF_FRAMES:-40}"
  if [ -x "$RT/probe/probe" ]; then
    for k in 10 32; do
      RAYBRIDGE_VALIDATION=0 step "probe k$k" 60 "$OUT/probe_gpu.log" "$RT/probe/probe" --width 2560 --height 1440 \
        --rays 64 --k "$k" --ground-tiles 64 --reps 7
    done
  fi
  read -r PW PH <<<"${RB_PERF_SIZE:-2560 1440}"
  perf_render() {  # NAME BINARY ARGS...
    local name="$1" bin="$2"
    shift 2
    RAYBRIDGE_VALIDATION=0 step "perf $name" 90 "$OUT/perf_gpu.log" "$bin" --width "$PW" --height "$PH" --dump "$@" \
      --out "$PDIR/$name"
  }
  # The same row with each earlier build carried as bin/raybridge-render-VARIANT, right after the current one: the
  # before/after rows, named SCENE-VARIANT__SUFFIX.
  perf_render_variants() {  # SCENE SUFFIX ARGS...
    local scene="$1" suffix="$2" vbin
    shift 2
    for vbin in "$RT"/bin/raybridge-render-*; do
      [ -x "$vbin" ] || continue
      perf_render "${scene}-${vbin##*/raybridge-render-}__${suffix}" "$vbin" "$@"
    done
  }
  for scene in perf demo; do
    sargs=()
    [ "$scene" = perf ] && sargs=(--perf-scene --models-from "$SCENES")
    for preset in ${RB_PERF_PRESETS:-hard-shadows low medium high ultra}; do
      perf_render "${scene}__hybrid__$preset" "$RT/bin/raybridge-render" "${sargs[@]}" --preset "$preset" \
        --frames "$PFRAMES"
      case " ${RB_PERF_VARIANT_PRESETS:-hard-shadows low ultra} " in *" $preset "*) ;; *) continue ;; esac
      perf_render_variants "$scene" "hybrid__$preset" "${sargs[@]}" --preset "$preset" --frames "$PFRAMES"
    done
    [ "${RB_PERF_EXTRAS:-1}" = 1 ] || continue
    for preset in low ultra; do
      perf_render "${scene}__raster__$preset" "$RT/bin/raybridge-render" "${sargs[@]}" --mode raster \
        --preset "$preset" --frames "$PFRAMES"
    done
    # Pure ray tracing (primary rays shaded, no G-buffer; the preset does not apply), and the shadow pass's tile
    # classifier against the same binary's default.
    perf_render "${scene}__raytraced__none" "$RT/bin/raybridge-render" "${sargs[@]}" --mode raytraced \
      --preset none --frames "$PFRAMES"
    for preset in hard-shadows ultra; do
      perf_render "${scene}__hybrid__${preset}__classifier" "$RT/bin/raybridge-render" "${sargs[@]}" \
        --preset "$preset" --tile-classifier --frames "$PFRAMES"
    done
  done
  for mode in hybrid raster raytraced; do
    [ "${RB_PERF_EXTRAS:-1}" = 1 ] || break
    for preset in low ultra; do
      [ "$mode" = raytraced ] && [ "$preset" = ultra ] && continue  # the preset does not apply
      perf_render "perf__${mode}__${preset}__path" "$RT/bin/raybridge-render" --perf-scene --models-from "$SCENES" \
        --mode "$mode" --preset "$preset" --camera-path "$ROOT/scripts/gpu/perf_flythrough.json" \
        --frames "${RB_PERF_PATH_FRAMES:-240}"
      # RB_PERF_PATH_VARIANTS=1: the earlier builds along the path too (hybrid only).
      [ "${RB_PERF_PATH_VARIANTS:-0}" = 1 ] && [ "$mode" = hybrid ] || continue
      perf_render_variants perf "${mode}__${preset}__path" --perf-scene --models-from "$SCENES" --mode "$mode" \
        --preset "$preset" --camera-path "$ROOT/scripts/gpu/perf_flythrough.json" --frames "${RB_PERF_PATH_FRAMES:-240}"
    done
  done
  # Cost curves (ultra, 20 frames each): resolution, triangles (the ground alone, 10k to 10M) and instances (more
  # copies of the models). Row tags: res, tri, inst.
  if [ "${RB_PERF_CURVES:-1}" = 1 ]; then
    for size in "1280 720" "1920 1080" "3840 2160"; do
      read -r cw ch <<<"$size"
      RAYBRIDGE_VALIDATION=0 step "perf res $cw" 90 "$OUT/perf_gpu.log" "$RT/bin/raybridge-render" --width "$cw" \
        --height "$ch" --dump --perf-scene --models-from "$SCENES" --preset ultra --frames 20 \
        --out "$PDIR/perf-${cw}x${ch}__hybrid__ultra__res"
    done
    for n in 70 224 708 2236; do
      perf_render "ground-n${n}__hybrid__ultra__tri" "$RT/bin/raybridge-render" --perf-scene --perf-ground-only \
        --perf-ground "$n" --preset ultra --frames 20
    done
    for k in 4 16; do
      perf_render "perf-x${k}__hybrid__ultra__inst" "$RT/bin/raybridge-render" --perf-scene --models-from "$SCENES" \
        --perf-copies "$k" --preset ultra --frames 20
    done
  fi
  read -r -a PBENCH <<<"${RB_PERF_BENCH_ARGS:---full}"
  if [ "${RB_PERF_BENCHES:-1}" = 1 ]; then
    RAYBRIDGE_VALIDATION=0 step "perf tlas bench" 150 "$OUT/perf_gpu.log" "$RT/bin/raybridge-bench" --scenario tlas \
      "${PBENCH[@]}" --out "$OUT/perf_tlas_gpu.json"
    RAYBRIDGE_VALIDATION=0 step "perf trace bench" 90 "$OUT/perf_gpu.log" "$RT/bin/raybridge-bench" --scenario trace \
      "${PBENCH[@]}" --out "$OUT/perf_trace_gpu.json"
  fi
  step "perf report" 30 "$OUT/perf_gpu.log" python3 "$ROOT/scripts/perf_report.py" --probe-log "$OUT/probe_gpu.log" \
    --renders "$PDIR" --command "bash scripts/gpu/run_remote.sh perf" --out "$OUT/perf_gpu.json"
  grep -E '^(perf|demo)|trace (primary|stress)|GPU ms|^in place|^device copy|^copy' "$OUT/perf_gpu.log" | head -n 80
  tar -C "$PDIR" -czf "$OUT/perf_render_gpu.tar.gz" --exclude='*.exr' --exclude='*.png' . 2>/dev/null
fi
# ---- motion: raybridge-effects-bench --scenario motion (docs/effects.md, "Motion") at RB_MOTION_SIZE (default
# 2560x1440), every case at 1, 4 and 16 rays, with the walking characters from the carried models; the JSON and the
# teleport strip's PNGs come back as motion_gpu.json and motion_images_gpu.tar.gz. RB_MOTION_ARGS adds arguments
# (e.g. --no-anti-lag). Validation off. Run only when named (not part of all).
if [[ ",$MODE," == *,motion,* ]]; then
  : >"$OUT/motion_gpu.log"
  MIMG="$(mktemp -d)"
  read -r MW MH <<<"${RB_MOTION_SIZE:-2560 1440}"
  read -r -a MARGS <<<"${RB_MOTION_ARGS:-}"
  RAYBRIDGE_VALIDATION=0 step "effects motion" "${RB_MOTION_SECONDS:-420}" "$OUT/motion_gpu.log" \
    "$RT/bin/raybridge-effects-bench" --scenario motion --width "$MW" --height "$MH" --scenes "$SCENES" \
    --images "$MIMG" --out "$OUT/motion_gpu.json" "${MARGS[@]}"
  grep -E '^motion:' "$OUT/motion_gpu.log" | grep -v reference | head -n 120
  tar -C "$MIMG" -czf "$OUT/motion_images_gpu.tar.gz" . 2>/dev/null
fi
# ---- adaptive: docs/performance.md's "trace only where needed" and half resolution. The probe, then
# raybridge-effects-bench --scenario adaptive (uniform against adaptive rays after 8 accumulated frames) and the
# speed-vs-error sweep of AO and reflections (full and half resolution rows) at RB_ADAPTIVE_SIZE, then the Ultra
# preset on the performance and demo scenes with per-effect time targets and half resolution (RB_ADAPTIVE_ULTRA:
# `uniform` is the thesis's Ultra, AO at full resolution; `preset` is the preset as it is, AO at half resolution).
# RB_ADAPTIVE_BENCH=0 leaves the two effects-bench sweeps out (the Ultra rows only); RB_ADAPTIVE_HALF=0 leaves out
# the second (half resolution) alone.
# perf_report.py writes adaptive_perf_gpu.json from the renders. Validation off.
if want adaptive; then
  : >"$OUT/adaptive_gpu.log"
  ADIR="$(mktemp -d)"
  read -r AW AH <<<"${RB_ADAPTIVE_SIZE:-2560 1440}"
  if [ -x "$RT/probe/probe" ]; then
    RAYBRIDGE_VALIDATION=0 step "probe k10" 60 "$OUT/probe_gpu.log" "$RT/probe/probe" --width 2560 --height 1440 \
      --rays 64 --k 10 --ground-tiles 64 --reps 7
  fi
  [ "${RB_ADAPTIVE_BENCH:-1}" = 1 ] && RAYBRIDGE_VALIDATION=0 step "effects adaptive" 200 "$OUT/adaptive_gpu.log" "$RT/bin/raybridge-effects-bench" \
    --scenario adaptive --effects shadows,ao --width "$AW" --height "$AH" --out "$OUT/effects_adaptive_gpu.json"
  [ "${RB_ADAPTIVE_BENCH:-1}" = 1 ] && [ "${RB_ADAPTIVE_HALF:-1}" = 1 ] && RAYBRIDGE_VALIDATION=0 step "effects half" 200 "$OUT/adaptive_gpu.log" "$RT/bin/raybridge-effects-bench" \
    --effects ao,reflections --width "$AW" --height "$AH" --out "$OUT/effects_half_gpu.json"
  AFRAMES="${RB_PERF_FRAMES:-40}"
  for scene in perf demo; do
    sargs=()
    [ "$scene" = perf ] && sargs=(--perf-scene --models-from "$SCENES")
    while IFS='|' read -r tag vargs; do
      [ -n "$tag" ] || continue
      read -r -a va <<<"$vargs"
      RAYBRIDGE_VALIDATION=0 step "adaptive ${scene} ${tag}" 90 "$OUT/adaptive_gpu.log" "$RT/bin/raybridge-render" \
        --width "$AW" --height "$AH" --dump "${sargs[@]}" --preset ultra --frames "$AFRAMES" "${va[@]}" \
        --out "$ADIR/${scene}__hybrid__ultra__${tag}"
    done <<<"${RB_ADAPTIVE_ULTRA:-uniform|--half-res none
preset|
adaptive|--adaptive ao,shadows
half|--half-res ao,reflections
budget|--adaptive ao=0.6,shadows=0.5 --half-res ao,reflections
budget-tight|--adaptive ao=0.5,shadows=0.4 --half-res ao,reflections}"
  done
  step "adaptive report" 30 "$OUT/adaptive_gpu.log" python3 "$ROOT/scripts/perf_report.py" \
    --probe-log "$OUT/probe_gpu.log" --renders "$ADIR" --command "bash scripts/gpu/run_remote.sh adaptive" \
    --out "$OUT/adaptive_perf_gpu.json"
  grep -E '^(shadows|ao)_adaptive:|^(ao|reflections):|GPU ms|Raybridge' "$OUT/adaptive_gpu.log" | head -n 80
fi
# ---- soak: raybridge-bench --scenario soak, 10,000 frames with validation off, then 2,000 with validation on.
if want soak; then
  : >"$OUT/soak_gpu.log"
  RAYBRIDGE_VALIDATION=0 step "soak" 300 "$OUT/soak_gpu.log" "$RT/bin/raybridge-bench" --scenario soak \
    --frames "${RB_SOAK_FRAMES:-10000}" --out "$OUT/soak_gpu.json"
  RAYBRIDGE_VALIDATION=1 step "soak validation" 200 "$OUT/soak_gpu.log" "$RT/bin/raybridge-bench" --scenario soak \
    --frames 2000 --out "$OUT/soak_validation_gpu.json"
  grep -E 'soak|growth|handles|validation' "$OUT/soak_gpu.log" | tail -n 30
fi
# ---- tests (validation on) ---------------------------------------------------------------------------------
if want tests; then
  : >"$OUT/tests_gpu.log"
  while IFS='|' read -r name exe args; do
    [ -n "$name" ] || continue
    # RB_TESTS="NAME ...": only those executables; RB_TEST_ARGS replaces their arguments (a Catch2 tag filter).
    [ -z "${RB_TESTS:-}" ] || [[ " $RB_TESTS " == *" $name "* ]] || continue
    [ -z "${RB_TEST_ARGS:-}" ] || args="$RB_TEST_ARGS"
    read -r -a targs <<<"$args"
    [ "$name" = bench_smoke ] && targs+=(--scenes "$SCENES" --out "$(mktemp -d)/bench_smoke_gpu.json")
    RAYBRIDGE_VALIDATION=1 step "test $name" 240 "$OUT/tests_gpu.log" "$RT/bin/$exe" "${targs[@]}"
  done <"$RT/tests.txt"
  grep -E '^(All tests passed|test cases:)|FAILED|validation\]' "$OUT/tests_gpu.log" | head -n 40
fi
# ---- tlas: raybridge-bench --scenario tlas --full alone (docs/performance.md's TLAS table), into tlas_gpu.json,
# and --scenario tlas-motion (its "TLAS refits" table) into tlas_motion_gpu.json.
if [[ ",$MODE," == *,tlas,* ]]; then  # only when named: `bench` runs it with every other scenario
  RAYBRIDGE_VALIDATION=0 step "tlas bench" 150 "$OUT/tlas_gpu.log" "$RT/bin/raybridge-bench" --scenario tlas --full \
    --out "$OUT/tlas_gpu.json"
  grep -E 'variant|in place|device copy|copy\+|gpuMsAt10k' "$OUT/tlas_gpu.log" | head -n 30
  # docs/performance.md's "TLAS refits" table: refitted, rebuilt and adaptive TLASes while instances scatter.
  RAYBRIDGE_VALIDATION=0 step "tlas-motion bench" 150 "$OUT/tlas_motion_gpu.log" "$RT/bin/raybridge-bench" \
    --scenario tlas-motion --full --out "$OUT/tlas_motion_gpu.json"
  grep -A40 '^== tlas-motion' "$OUT/tlas_motion_gpu.log" | head -n 40
  # Earlier builds carried as bin/raybridge-bench-VARIANT (prepare.sh EXTRA_BINS): their tlas-motion runs in the
  # same session, then the current build's once more, so a change of the policy's measure is compared in one run
  # (host times included). Into tlas_motion_gpu_VARIANT.json and tlas_motion_gpu_again.json, logs appended.
  shopt -s nullglob
  earlier=("$RT"/bin/raybridge-bench-*)
  shopt -u nullglob
  if [ "${#earlier[@]}" -gt 0 ]; then
    for bin in "${earlier[@]}"; do
      variant="${bin##*/raybridge-bench-}"
      RAYBRIDGE_VALIDATION=0 step "tlas-motion bench ($variant)" 150 "$OUT/tlas_motion_gpu.log" "$bin" \
        --scenario tlas-motion --full --out "$OUT/tlas_motion_gpu_$variant.json"
    done
    RAYBRIDGE_VALIDATION=0 step "tlas-motion bench (again)" 150 "$OUT/tlas_motion_gpu.log" "$RT/bin/raybridge-bench" \
      --scenario tlas-motion --full --out "$OUT/tlas_motion_gpu_again.json"
    grep -A12 '^== tlas-motion: TLAS per frame' "$OUT/tlas_motion_gpu.log" | grep -E 'variant|adaptive|rebuild|refit'
  fi
fi
# ---- trace: docs/performance.md's primary-pass rows. The probe (~1M triangles) at 2560x1440 and 1920x1080, then
# raybridge-bench --scenario trace --full at both sizes (its third view is the probe's own scene and camera), by
# the current build and by each earlier one carried as bin/raybridge-bench-VARIANT (prepare.sh EXTRA_BINS), in
# RB_TRACE_ROUNDS rounds (default 2) that rotate their order. Into trace_gpu.log and trace_<size>_<bin>_<round>.json.
if [[ ",$MODE," == *,trace,* ]]; then
  : >"$OUT/trace_gpu.log"
  TDIR="$(mktemp -d)"
  bins=("$RT/bin/raybridge-bench")
  for vbin in "$RT"/bin/raybridge-bench-*; do [ -x "$vbin" ] && bins+=("$vbin"); done
  for size in "2560 1440" "1920 1080"; do
    read -r tw th <<<"$size"
    if [ -x "$RT/probe/probe" ]; then
      RAYBRIDGE_VALIDATION=0 step "probe k32 ${tw}" 60 "$OUT/trace_gpu.log" "$RT/probe/probe" --width "$tw" \
        --height "$th" --rays 64 --k 32 --ground-tiles 64 --reps 7
    fi
    for round in $(seq 1 "${RB_TRACE_ROUNDS:-2}"); do
      n=${#bins[@]}
      for ((i = 0; i < n; ++i)); do
        b="${bins[$(((i + round - 1) % n))]}"
        tag="${b##*/raybridge-bench}"
        tag="${tag#-}"
        RAYBRIDGE_VALIDATION=0 step "trace ${tw} ${tag:-current} r$round" 90 "$OUT/trace_gpu.log" "$b" \
          --scenario trace --full --width "$tw" --height "$th" --out "$TDIR/trace_${tw}_${tag:-current}_$round.json"
      done
    done
  done
  tar -C "$TDIR" -czf "$OUT/trace_gpu.tar.gz" . 2>/dev/null
  grep -E '^== trace [0-9]|^ *(ground|sky|probe scene)|^trace primary|pixels hit' "$OUT/trace_gpu.log" | head -n 80
fi
# ---- inject: raybridge_tests' failure-injection cases ([inject]), left out of `tests`: every SDK allocation site
# fails in turn, and every pass is recreated after each (minutes of pipeline compilation on the GPU).
if [[ ",$MODE," == *,inject,* ]]; then
  : >"$OUT/inject_gpu.log"
  RAYBRIDGE_VALIDATION=1 step "test raybridge_tests [inject]" "${RB_INJECT_LIMIT:-540}" "$OUT/inject_gpu.log" \
    "$RT/bin/raybridge_tests" "[inject]" -d yes
  grep -E '^(All tests passed|test cases:)|FAILED|validation\]|scenario|sites' "$OUT/inject_gpu.log" | head -n 40
fi

finish
