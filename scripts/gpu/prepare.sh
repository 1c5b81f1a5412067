#!/usr/bin/env bash
# Builds Raybridge for the GPU machine and assembles .devcarry/, the folder the device tool carries there
# (see scripts/gpu/README.md). Runs here, on the Debian 12 build machine (x86-64, like the GPU machine).
#
#   scripts/gpu/prepare.sh            # Release build in build-gpu/ (engine included if it builds), then .devcarry/
#
# Environment:
#   JOBS=2               parallel compile jobs (the build machine is shared: keep it at 2)
#   BUILD_DIR=build-gpu  build folder (gitignored)
#   SKIP_BUILD=1         reuse the existing build folder as it is
#   SKIP_ENGINE=1        build without samples/engine from the start (-DRAYBRIDGE_SKIP_ENGINE=ON)
#   SCENES_DIR=...       glTF models to carry (default ../shared/scenes beside the checkout); geometry only
#   EXTRA_BINS="F ..."   more executables to carry into bin/ (e.g. raybridge-render-base for run_remote.sh perf)
#
# .devcarry/ layout (files over 256 KiB are stored gzipped as NAME.gz; run_remote.sh unpacks them):
#   bin/      raybridge-bench, the test executables, raybridge-render and other sample executables
#   lib/      shared libraries the binaries and the layer need, outside glibc and the C++ runtime (per ldd)
#   lib-fallback/  libstdc++ and libgcc_s, used there only if the machine's own are too old
#   layers/   VkLayer_khronos_validation.json (library_path relative to itself) and its .so
#   debs/     Debian's libvulkan1 and the libglvnd family (amd64; NVIDIA's ICD, libGLX_nvidia, needs libGLdispatch), unpacked with dpkg -x on the GPU machine (it has no loader)
#   data/scenes/  .gltf/.glb/.bin of the glTF models (no textures)
#   tests.txt     one test per line: NAME|BINARY|ARGS, run with RAYBRIDGE_VALIDATION=1
#   source_dir.txt  the source path compiled into the binaries (tests look for <it>/../shared/scenes)
#   manifest.txt    what was built, from which commit, when, and the folder's size
set -euo pipefail

ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
cd "$ROOT"
BUILD="${BUILD_DIR:-build-gpu}"
JOBS="${JOBS:-2}"
CARRY="$ROOT/.devcarry"
LIMIT_MIB=60
SCENES="${SCENES_DIR:-$ROOT/../shared/scenes}"
LAYER_SO=/usr/lib/x86_64-linux-gnu/libVkLayer_khronos_validation.so
LAYER_JSON=/usr/share/vulkan/explicit_layer.d/VkLayer_khronos_validation.json

log() { echo "[prepare] $*" >&2; }
die() { echo "[prepare] error: $*" >&2; exit 1; }

[ "$(uname -m)" = x86_64 ] || die "the GPU machine is x86-64; build there or on an x86-64 machine"

# ---- 1. Release build --------------------------------------------------------------------------------------
# Logs live in the build folder (gitignored): configure.log and build.log.
configure() {
  mkdir -p "$BUILD"
  cmake -S "$ROOT" -B "$BUILD" -G Ninja -DCMAKE_BUILD_TYPE=Release -DRAYBRIDGE_BUILD_TESTS=ON "$@" >"$BUILD/configure.log" 2>&1
}
ENGINE=unknown
if [ "${SKIP_BUILD:-0}" = 1 ]; then
  [ -f "$BUILD/build.ninja" ] || die "SKIP_BUILD=1 but $BUILD has no build"
  ENGINE=$(grep -q '^RAYBRIDGE_SKIP_ENGINE:[A-Z]*=ON' "$BUILD/CMakeCache.txt" && echo skipped || echo built)
  log "reusing $BUILD (engine $ENGINE)"
else
  built=0
  if [ "${SKIP_ENGINE:-0}" != 1 ]; then
    log "configuring $BUILD (Release, tests, engine); log in $BUILD/configure.log"
    if configure -DRAYBRIDGE_SKIP_ENGINE=OFF; then
      log "building with ninja -j$JOBS; log in $BUILD/build.log"
      if ninja -C "$BUILD" -j"$JOBS" >"$BUILD/build.log" 2>&1; then
        built=1
        ENGINE=built
      else
        log "the build failed with the engine (tail of $BUILD/build.log below); retrying with -DRAYBRIDGE_SKIP_ENGINE=ON"
        grep -E 'error|FAILED' "$BUILD/build.log" | head -n 10 >&2 || true
      fi
    else
      log "configuring with the engine failed (see $BUILD/configure.log); retrying with -DRAYBRIDGE_SKIP_ENGINE=ON"
    fi
  fi
  if [ "$built" = 0 ]; then
    rm -rf "$BUILD"  # no stale engine binaries may be collected below
    configure -DRAYBRIDGE_SKIP_ENGINE=ON || { tail -n 20 "$BUILD/configure.log" >&2; die "configure failed"; }
    ninja -C "$BUILD" -j"$JOBS" >"$BUILD/build.log" 2>&1 || { tail -n 30 "$BUILD/build.log" >&2; die "build failed"; }
    ENGINE=skipped
  fi
  log "build done (engine $ENGINE)"
fi

# ---- 2. binaries -------------------------------------------------------------------------------------------
rm -rf "$CARRY"
mkdir -p "$CARRY/bin" "$CARRY/lib" "$CARRY/layers" "$CARRY/debs" "$CARRY/data"
BENCH="$BUILD/samples/bench/raybridge-bench"
[ -x "$BENCH" ] || die "$BENCH was not built"
# Executables of the project: everything executable under tests/, samples/, adapters/ and tools/ of the build,
# outside CMake's own folders, that is an ELF program (not a library or script).
mapfile -t EXES < <(for d in tests samples adapters tools; do
    [ -d "$BUILD/$d" ] && find "$BUILD/$d" -path '*/CMakeFiles' -prune -o -type f -perm -u+x -print
  done | while read -r f; do
    case "$f" in *.so|*.so.*|*.a|*.sh|*.cmake) continue ;; esac
    file -b "$f" | grep -q 'ELF 64-bit LSB pie executable\|ELF 64-bit LSB executable' && echo "$f"
  done | sort -u)
[ -x "$BUILD/raybridge-render" ] && EXES+=("$BUILD/raybridge-render")
# EXTRA_BINS="FILE ...": more executables to carry as they are, e.g. an earlier build's render command renamed
# raybridge-render-base, the "before" of run_remote.sh perf.
for f in ${EXTRA_BINS:-}; do
  [ -x "$f" ] || die "EXTRA_BINS: $f is not an executable"
  EXES+=("$f")
done
for f in "${EXES[@]}"; do
  name=$(basename "$f")
  [ -e "$CARRY/bin/$name" ] && die "two executables named $name"
  cp "$f" "$CARRY/bin/$name"
done
log "binaries: $(cd "$CARRY/bin" && ls | tr '\n' ' ')"

# Tests: executables named *test* (Catch2 or plain), each run whole, plus the benchmark smoke run (validation on).
: >"$CARRY/tests.txt"
for f in "$CARRY"/bin/*; do
  name=$(basename "$f")
  # Catch2's -d yes prints each test case's name as it ends: a validation message printed by the layer is then
  # followed by the name of the test that caused it.
  # The failure-injection cases recreate every pass once per allocation site (several hundred pipeline
  # compilations): on the GPU they take minutes, so run_remote.sh runs them on their own (mode inject).
  case "$name" in
    raybridge_tests) echo "$name|$name|-d yes ~[inject]" >>"$CARRY/tests.txt" ;;
    *test*) echo "$name|$name|-d yes" >>"$CARRY/tests.txt" ;;
  esac
done
echo "bench_smoke|raybridge-bench|--quick --scenario all" >>"$CARRY/tests.txt"

# The independent raw-rate probe (../shared/tools/rt-probe), run in the same GPU run as the benchmarks.
PROBE_SRC="$ROOT/../shared/tools/rt-probe"
if [ -f "$PROBE_SRC/build.sh" ]; then
  sh "$PROBE_SRC/build.sh" "$CARRY/probe" >/dev/null && log "probe: built into .devcarry/probe"
else
  log "no rt-probe at $PROBE_SRC: the GPU run has no raw-rate baseline"
fi
echo "$ROOT" >"$CARRY/source_dir.txt"

# ---- 3. validation layer -----------------------------------------------------------------------------------
[ -f "$LAYER_SO" ] && [ -f "$LAYER_JSON" ] || die "the validation layer is not installed ($LAYER_SO, $LAYER_JSON)"
cp "$LAYER_SO" "$CARRY/layers/"
sed -E 's#"library_path"[[:space:]]*:[[:space:]]*"[^"]*"#"library_path": "./libVkLayer_khronos_validation.so"#' \
  "$LAYER_JSON" >"$CARRY/layers/VkLayer_khronos_validation.json"
grep -q '"library_path": "./libVkLayer_khronos_validation.so"' "$CARRY/layers/VkLayer_khronos_validation.json" \
  || die "could not rewrite library_path in the layer manifest"

# ---- 4. shared libraries (per ldd), outside glibc and the Vulkan loader ------------------------------------
is_system_lib() {
  case "$(basename "$1")" in
    linux-vdso*|ld-linux*|libc.so*|libm.so*|libpthread.so*|libdl.so*|librt.so*|libresolv.so*|libutil.so*) return 0 ;;
    libvulkan.so*) return 0 ;;  # from debs/ (the loader must match its ICD search, not be carried loose)
  esac
  return 1
}
missing=0
for f in "$CARRY"/bin/* "$CARRY/layers/libVkLayer_khronos_validation.so"; do
  while read -r lib path; do
    if [ "$path" = "not" ]; then
      log "warning: $(basename "$f") needs $lib, which ldd does not find here"
      missing=1
      continue
    fi
    is_system_lib "$lib" && continue
    [ -e "$CARRY/lib/$lib" ] || cp -L "$path" "$CARRY/lib/$lib"
  done < <(ldd "$f" | awk '/=>/ { print $1, $3 }')
done
[ "$missing" = 0 ] || die "unresolved libraries (see above)"
# The C++ runtime goes to lib-fallback/: run_remote.sh uses it only when the GPU machine's own libstdc++ is too
# old for the binaries (forcing an older one on the NVIDIA driver's libraries could break them).
mkdir -p "$CARRY/lib-fallback"
for lib in libstdc++.so.6 libgcc_s.so.1; do
  [ -e "$CARRY/lib/$lib" ] && mv "$CARRY/lib/$lib" "$CARRY/lib-fallback/$lib"
done
grep -aoh 'GLIBCXX_3\.4\.[0-9]*' "$CARRY"/bin/* "$CARRY"/lib/* "$CARRY"/layers/*.so | sort -uV | tail -n 1 \
  >"$CARRY/lib-fallback/GLIBCXX_NEEDED"
grep -aoh 'GLIBC_2\.[0-9]*' "$CARRY"/bin/* "$CARRY"/lib/* "$CARRY"/layers/*.so | sort -uV | tail -n 1 \
  >"$CARRY/lib-fallback/GLIBC_NEEDED"
log "needs $(cat "$CARRY/lib-fallback/GLIBCXX_NEEDED") and $(cat "$CARRY/lib-fallback/GLIBC_NEEDED")"
log "libraries: $(cd "$CARRY/lib" && ls | tr '\n' ' ')"

# ---- 5. the Vulkan loader package --------------------------------------------------------------------------
APT_OPTS=(-oAPT::Architecture=amd64 -oAPT::Architectures=amd64 -oDir::State::Lists=/tmp/amd64)
mkdir -p /tmp/amd64/partial
if ! (cd "$CARRY/debs" && apt-get "${APT_OPTS[@]}" download libvulkan1 libglvnd0 libglx0 libegl1 libgl1 libopengl0 libgles2 >/dev/null 2>&1); then
  log "apt-get download failed; updating the amd64 package lists and retrying"
  apt-get "${APT_OPTS[@]}" update -q >/dev/null
  (cd "$CARRY/debs" && apt-get "${APT_OPTS[@]}" download libvulkan1 libglvnd0 libglx0 libegl1 libgl1 libopengl0 libgles2) || die "could not download libvulkan1 and libglvnd"
fi
ls "$CARRY"/debs/libvulkan1_*_amd64.deb >/dev/null || die "no libvulkan1 amd64 .deb in debs/"

# ---- 6. data: glTF geometry (no textures) ------------------------------------------------------------------
if [ -d "$SCENES" ]; then
  (cd "$SCENES" && find . -mindepth 2 -maxdepth 2 -type f \( -name '*.gltf' -o -name '*.glb' -o -name '*.bin' \) -print0 |
    while IFS= read -r -d '' f; do mkdir -p "$CARRY/data/scenes/$(dirname "$f")"; cp "$f" "$CARRY/data/scenes/$f"; done)
  log "scenes: $(ls "$CARRY/data/scenes" | wc -l) models from $SCENES"
else
  log "no scenes at $SCENES: the bench will skip its glTF rows there"
fi

# ---- 7. compress what is large, check the size -------------------------------------------------------------
find "$CARRY" -type f -size +256k ! -name '*.deb' ! -name '*.gz' -exec gzip -9 {} +
bytes=$(du -sb "$CARRY" | cut -f1)
mib=$(( (bytes + 1048575) / 1048576 ))
{
  echo "built: $(date -u +%Y-%m-%dT%H:%M:%SZ) on $(hostname)"
  echo "commit: $(git -C "$ROOT" rev-parse HEAD 2>/dev/null || echo unknown) ($(git -C "$ROOT" status --porcelain 2>/dev/null | wc -l) paths modified or untracked)"
  echo "build: $BUILD (Release, engine $ENGINE)"
  echo "size: $bytes bytes ($mib MiB)"
  (cd "$CARRY" && find . -type f | sort | while read -r f; do printf '%10d  %s\n' "$(stat -c %s "$f")" "$f"; done)
} >"$CARRY/manifest.txt"
log ".devcarry: $mib MiB ($bytes bytes); manifest in .devcarry/manifest.txt"
[ "$mib" -le "$LIMIT_MIB" ] || die ".devcarry is $mib MiB, over the $LIMIT_MIB MiB limit"
echo "$mib"
