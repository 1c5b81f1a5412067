#!/usr/bin/env bash
# Builds the libFuzzer targets (tests/fuzz) into ./build-fuzz with clang, ASan and UBSan, and runs each for SECONDS
# (default 60). Exits non-zero when a target reports a finding (crash, leak, timeout, out-of-memory) or fails to
# run. Prints and writes build-fuzz/fuzz_report.json (per target: seconds, executions, corpus size, findings).
#   scripts/fuzz.sh [SECONDS]
# Corpora: each target keeps what it found in build-fuzz/fuzz/<target>/corpus (a later run resumes from it), seeded
# from tests/fuzz/corpus/<target> and, for the glTF loader, from the shared scenes ($RAYBRIDGE_SCENES, else
# ../shared/scenes beside the checkout) copied into a temporary folder; the scenes' buffers (.bin) are the only
# external files the loader may read then (RAYBRIDGE_FUZZ_GLTF_FILES). Findings: build-fuzz/fuzz/<target>/artifacts.
# Replay one: build-fuzz/tests/fuzz/<target>_fuzz <file>. Extra libFuzzer flags for every target: FUZZ_FLAGS="...".
set -euo pipefail
cd "$(dirname "$0")/.."
seconds="${1:-60}"
case "$seconds" in '' | *[!0-9]*) echo "fuzz: SECONDS must be a whole number, not '$seconds'" >&2; exit 2 ;; esac

# The build dependencies (a no-op when installed), then Debian's clang 14 with libFuzzer and the sanitizer runtimes.
bash scripts/setup.sh
fuzz_pkgs="clang libfuzzer-14-dev libclang-rt-14-dev"
if ! dpkg -s $fuzz_pkgs >/dev/null 2>&1; then
  SUDO=""
  if [ "$(id -u)" != 0 ]; then SUDO=sudo; fi
  export DEBIAN_FRONTEND=noninteractive
  $SUDO apt-get update -q
  $SUDO apt-get install -y -q --no-install-recommends $fuzz_pkgs
fi

launcher=()
if command -v ccache >/dev/null 2>&1; then
  launcher=(-DCMAKE_C_COMPILER_LAUNCHER=ccache -DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
fi
# -O1 -g with assertions on; the samples and the Catch2 tests are not part of this build.
cmake -S . -B build-fuzz -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  -DCMAKE_C_FLAGS_RELWITHDEBINFO="-O1 -g" -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -g" \
  -DCMAKE_C_COMPILER=clang -DCMAKE_CXX_COMPILER=clang++ "${launcher[@]}" \
  -DRAYBRIDGE_FUZZ=ON -DRAYBRIDGE_BUILD_TESTS=OFF -DRAYBRIDGE_BUILD_SAMPLES=OFF -DRAYBRIDGE_INSTALL=OFF >/dev/null
targets=(gltf_loader mesh_registration render_options camera_path)
cmake --build build-fuzz -j "$(nproc 2>/dev/null || echo 2)" --target "${targets[@]/%/_fuzz}"

work="$PWD/build-fuzz/fuzz"
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT

# The shared scenes as glTF seeds: the .gltf files that fit -max_len, their buffers in one folder of files the
# loader may read (their names differ across the scenes). Images are left out: decoding them (stb_image, not ours)
# would dominate every run.
gltf_max_len=262144
scenes="${RAYBRIDGE_SCENES:-$PWD/../shared/scenes}"
scene_seeds=()
scenes_failed=0
export RAYBRIDGE_FUZZ_GLTF_FILES="$tmp/gltf_files"
mkdir -p "$RAYBRIDGE_FUZZ_GLTF_FILES" "$tmp/gltf_scenes"
if [ -d "$scenes" ]; then
  copied=0
  while IFS= read -r -d '' f; do
    if [ "$(stat -c %s "$f")" -le "$gltf_max_len" ]; then
      cp "$f" "$tmp/gltf_scenes/" && copied=$((copied + 1))
    fi
  done < <(find "$scenes" -name '*.gltf' -print0)
  find "$scenes" -name '*.bin' -exec cp {} "$RAYBRIDGE_FUZZ_GLTF_FILES/" \;
  chmod -R u+w "$tmp"
  # Every scene runs once here (a finding counts like any other); only those that load in under 200 ms seed the
  # fuzzing, where a scene of a million vertices would take most of the time for little new coverage.
  mkdir -p "$work/gltf_loader"
  rm -f "$work/gltf_loader/scenes_log.txt"
  if [ "$copied" -gt 0 ] && ! build-fuzz/tests/fuzz/gltf_loader_fuzz -runs=1 -timeout=60 "$tmp/gltf_scenes"/*.gltf \
    >"$work/gltf_loader/scenes_log.txt" 2>&1; then
    echo "fuzz: a shared scene fails the glTF loader target (build-fuzz/fuzz/gltf_loader/scenes_log.txt)" >&2
    scenes_failed=1
  fi
  while read -r file ms; do
    if [ "$ms" -ge 200 ]; then rm -f "$file" && echo "fuzz: $(basename "$file") loads in $ms ms; not a seed"; fi
  done < <(sed -n 's/^Executed \(.*\) in \([0-9]*\) ms$/\1 \2/p' "$work/gltf_loader/scenes_log.txt" 2>/dev/null)
  scene_seeds=("$tmp/gltf_scenes")
  echo "fuzz: $(ls "$tmp/gltf_scenes" | wc -l) of $copied shared scenes from $scenes as glTF seeds"
else
  echo "fuzz: no shared scenes at $scenes (set RAYBRIDGE_SCENES); the glTF loader starts from its own seeds"
fi

declare -A max_len=([gltf_loader]=$gltf_max_len [mesh_registration]=4096 [render_options]=1024 [camera_path]=8192)
failed=$scenes_failed
for t in "${targets[@]}"; do
  dir="$work/$t"
  mkdir -p "$dir/corpus" "$dir/artifacts"
  rm -f "$dir/artifacts/"*
  seeds=("tests/fuzz/corpus/$t")
  if [ "$t" = gltf_loader ]; then seeds+=("${scene_seeds[@]}"); fi
  dict=()
  if [ -f "tests/fuzz/dict/$t.dict" ]; then dict=(-dict="tests/fuzz/dict/$t.dict"); fi
  echo "fuzz: $t for ${seconds}s"
  start=$(date +%s)
  set +e
  # shellcheck disable=SC2086
  "build-fuzz/tests/fuzz/${t}_fuzz" -max_total_time="$seconds" -timeout=10 -rss_limit_mb=4096 \
    -max_len="${max_len[$t]}" -print_final_stats=1 -artifact_prefix="$dir/artifacts/" "${dict[@]}" ${FUZZ_FLAGS:-} \
    "$dir/corpus" "${seeds[@]}" >"$dir/log.txt" 2>&1
  rc=$?
  set -e
  echo "$rc $(($(date +%s) - start))" >"$dir/status.txt"
  tail -n 4 "$dir/log.txt"
  [ "$rc" = 0 ] || failed=1
done

if python3 - "$work" "${targets[@]}" <<'EOF'
import json, os, re, sys
work, targets = sys.argv[1], sys.argv[2:]
report = {}
for t in targets:
    d = os.path.join(work, t)
    rc, seconds = (int(x) for x in open(os.path.join(d, "status.txt")).read().split())
    log = open(os.path.join(d, "log.txt"), errors="replace").read()
    m = re.search(r"stat::number_of_executed_units:\s*(\d+)", log)
    corpus = [os.path.join(d, "corpus", f) for f in os.listdir(os.path.join(d, "corpus"))]
    # slow-unit-* files are a note, not a finding.
    findings = sorted(os.path.join(d, "artifacts", f) for f in os.listdir(os.path.join(d, "artifacts"))
                      if not f.startswith("slow-unit-"))
    scenes_log = os.path.join(d, "scenes_log.txt")  # the shared scenes, each run once before fuzzing
    if os.path.exists(scenes_log) and "SUMMARY:" in open(scenes_log, errors="replace").read():
        findings.append(scenes_log)
    summary = re.findall(r"^SUMMARY: .*$", log, re.M)
    report[t] = {"seconds": seconds, "executions": int(m.group(1)) if m else None,
                 "corpus_files": len(corpus), "corpus_bytes": sum(os.path.getsize(f) for f in corpus),
                 "findings": findings, "exit_code": rc,
                 "summary": summary[-1] if summary else ""}
    if rc != 0 and not findings and not summary:
        report[t]["summary"] = "failed to run (exit %d); see %s" % (rc, os.path.join(d, "log.txt"))
text = json.dumps(report, indent=2)
print(text)
with open(os.path.join(os.path.dirname(work), "fuzz_report.json"), "w") as f:
    f.write(text + "\n")
sys.exit(1 if any(r["findings"] for r in report.values()) else 0)
EOF
then :; else failed=1; fi
if [ "$failed" != 0 ]; then
  echo "fuzz: FAILED: a target found something or did not run (build-fuzz/fuzz_report.json)" >&2
  exit 1
fi
echo "fuzz: no findings"
