#!/usr/bin/env bash
# The sanitizer job of CI (.ci/run): builds with Clang's sanitizers and runs the tests on the default device
# (lavapipe where there is no GPU) with the Vulkan validation layer on. Any sanitizer report (in the test programs
# or in the programs they start), any validation error and any failed test makes the script exit non-zero.
#   scripts/sanitize.sh [asan|tsan|all]     (default all)
#   asan: AddressSanitizer + UndefinedBehaviorSanitizer + LeakSanitizer, in ./build-asan: every test program
#         that ctest runs (raybridge_tests but its 8K case, sample_engine_tests, pose_reference_tests,
#         minimal_integration_test, the adapter's and the tools' tests, which start the sanitized raybridge-render)
#         and the three benchmark smoke runs.
#   tsan: ThreadSanitizer, in ./build-tsan: the calls documented as callable from several threads
#         (raybridge_tests "[threads]": registerMesh/releaseMesh on streaming threads, validation messages).
# What runs and why, the timings and the suppressions: docs/reliability.md, "Sanitizers".
# JOBS=N sets the build parallelism (default: the number of cores).
set -euo pipefail
cd "$(dirname "$0")/.."
root="$(pwd)"

what="${1:-all}"
case "$what" in
  asan | tsan | all) ;;
  -h | --help) sed -n '2,12p' "$0" | sed 's/^# \{0,1\}//'; exit 0 ;;
  *) echo "sanitize: unknown argument '$what' (use asan, tsan or all)" >&2; exit 2 ;;
esac
jobs="${JOBS:-$(nproc 2>/dev/null || echo 2)}"

# --- Dependencies: scripts/setup.sh's, plus Clang with its sanitizer runtimes and llvm-symbolizer (stacks). ---
bash scripts/setup.sh
have_sanitizers() {
  command -v clang++ >/dev/null 2>&1 && command -v llvm-symbolizer >/dev/null 2>&1 || return 1
  local rt
  for rt in asan ubsan_standalone tsan; do
    [ -f "$(clang++ --print-file-name="libclang_rt.$rt-x86_64.a")" ] || return 1
  done
}
if ! have_sanitizers; then
  SAN_PKGS="clang libclang-rt-dev llvm"  # Debian 12: Clang 14, its runtimes (libclang-rt-14-dev), llvm-symbolizer
  SUDO=""
  if [ "$(id -u)" != 0 ]; then SUDO=sudo; fi
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -q --no-install-recommends $SAN_PKGS
fi

launcher=()
if command -v ccache >/dev/null 2>&1; then
  launcher=(-DCMAKE_C_COMPILER_LAUNCHER=ccache -DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
fi

# configure DIR SANITIZERS: a RelWithDebInfo Clang build (optimised like CI's Release build, with file and line in
# the reports) whose every target gets -fsanitize=SANITIZERS (the RAYBRIDGE_SANITIZE option of CMakeLists.txt).
# Also builds DIR/keep_loaded.so (scripts/sanitizers/keep_loaded.c), without sanitizers: it is preloaded, not linked.
configure() {
  cmake -S . -B "$1" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_C_COMPILER=clang \
    -DCMAKE_CXX_COMPILER=clang++ "${launcher[@]}" -DRAYBRIDGE_BUILD_TESTS=ON -DRAYBRIDGE_SANITIZE="$2" >/dev/null
  clang -shared -fPIC -O2 -o "$1/keep_loaded.so" scripts/sanitizers/keep_loaded.c
}

# Reports go to files (log_path), one per process that reports, so that a report in a program a test starts
# (raybridge-render) fails the job even where the test only checks that the program failed. After each program,
# any such file is printed and fails the job.
reports=""
check_reports() {
  local found=0 f
  for f in "$reports".*; do
    [ -e "$f" ] || continue
    found=1
    echo "sanitize: sanitizer report $f:" >&2
    cat "$f" >&2
  done
  return "$found"
}

# run NAME COMMAND...: runs one program (at most 30 minutes, like ctest's timeout in test.sh) and reports its
# time; a failure, a timeout or a sanitizer report ends the script.
run() {
  local name="$1" start rc=0
  shift
  echo "sanitize: running $name"
  start=$(date +%s)
  timeout -k 30 1800 "$@" || rc=$?
  echo "sanitize: $name took $(($(date +%s) - start)) s, exit code $rc"
  check_reports || { echo "sanitize: $name: sanitizer report (above)" >&2; exit 1; }
  [ "$rc" -eq 0 ] || { echo "sanitize: $name failed (exit code $rc)" >&2; exit 1; }
}

export RAYBRIDGE_VALIDATION=1
supp="$root/scripts/sanitizers"
export ASAN_SYMBOLIZER_PATH TSAN_SYMBOLIZER_PATH
ASAN_SYMBOLIZER_PATH="$(command -v llvm-symbolizer)"
TSAN_SYMBOLIZER_PATH="$ASAN_SYMBOLIZER_PATH"

if [ "$what" = asan ] || [ "$what" = all ]; then
  start=$(date +%s)
  configure build-asan address,undefined
  cmake --build build-asan -j "$jobs" --target raybridge_tests sample_engine_tests pose_reference_tests \
    minimal_integration_test raybridge_adapter_tests raybridge_render_command_tests raybridge_render_conformance_tests \
    raybridge_animated_conformance_tests raybridge_far_origin_tests raybridge_lights_conformance_tests \
    raybridge_camera_path_tests raybridge_flythrough_tests raybridge_render_malformed_input_tests \
    raybridge-bench raybridge-effects-bench raybridge-animated-bench
  echo "sanitize: asan build took $(($(date +%s) - start)) s"
  start=$(date +%s)
  reports="$root/build-asan/sanitizer-report"
  rm -f "$reports".*
  (
    # halt_on_error/abort_on_error: the first report ends the program (abort: Catch2 names the running test).
    # detect_leaks: LeakSanitizer at exit, with lsan.supp for the uninstrumented Vulkan layer.
    # protect_shadow_gap stays on: lavapipe, its LLVM JIT and the validation layer load and run with it.
    export ASAN_OPTIONS="detect_leaks=1:halt_on_error=1:abort_on_error=1:detect_stack_use_after_return=1:check_initialization_order=1:strict_init_order=1:log_path=$reports"
    export LSAN_OPTIONS="suppressions=$supp/lsan.supp:print_suppressions=0"
    export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1:log_path=$reports"
    # The Vulkan loader unloads the driver and the layers before the leak check at exit: see keep_loaded.c.
    export LD_PRELOAD="$root/build-asan/keep_loaded.so"
    b=build-asan
    # Two processes on the two cores, split by their times on the CI machine: the allocation-failure injection and
    # two short tools in the background (about 280 s on 2026-12-07), the rest of raybridge_tests and the other
    # programs here (about 390 s). The 8K case ([large], 210 s under ASan) is left to ctest: it runs
    # the host code the small sizes run, at a size that only costs time here.
    (
      run "raybridge_tests [inject]" $b/tests/raybridge_tests "[inject]"
      for t in flythrough render_malformed_input; do
        run "raybridge_${t}_tests" "$b/tools/tests/raybridge_${t}_tests"
      done
    ) >"$b/raybridge_tests_inject.log" 2>&1 &
    background=$!
    trap 'kill "$background" 2>/dev/null || true' EXIT  # a failure below does not leave it running
    run "raybridge_tests (but [inject] and [large])" $b/tests/raybridge_tests "~[inject]~[large]"
    run sample_engine_tests $b/samples/engine/sample_engine_tests
    run pose_reference_tests $b/samples/engine/tests/reference/pose_reference_tests
    run minimal_integration_test $b/samples/minimal_integration/tests/minimal_integration_test
    run raybridge_adapter_tests $b/adapters/tests/raybridge_adapter_tests
    for t in render_command render_conformance animated_conformance far_origin lights_conformance camera_path; do
      run "raybridge_${t}_tests" "$b/tools/tests/raybridge_${t}_tests"
    done
    run bench_smoke $b/samples/bench/raybridge-bench --quick --scenario all --out $b/bench_smoke.json
    run effects_bench_smoke $b/tools/effects_bench/raybridge-effects-bench --quick --out $b/effects_smoke.json
    run animated_bench_smoke $b/tools/animated_bench/raybridge-animated-bench --quick --out $b/animated_smoke.json
    background_rc=0
    wait "$background" || background_rc=$?
    cat "$b/raybridge_tests_inject.log"
    [ "$background_rc" -eq 0 ] || { echo "sanitize: the background runs failed (exit code $background_rc)" >&2; exit 1; }
  )
  echo "sanitize: asan runs took $(($(date +%s) - start)) s"
fi

if [ "$what" = tsan ] || [ "$what" = all ]; then
  start=$(date +%s)
  configure build-tsan thread
  cmake --build build-tsan -j "$jobs" --target raybridge_tests
  echo "sanitize: tsan build took $(($(date +%s) - start)) s"
  start=$(date +%s)
  reports="$root/build-tsan/sanitizer-report"
  rm -f "$reports".*
  (
    # halt_on_error without abort_on_error: TSan then exits with code 66. An abort would run Catch2's SIGABRT
    # handler inside TSan's report, which hung the process here.
    # ignore_noninstrumented_modules: what the uninstrumented libraries (lavapipe, LLVM, the loader, the
    # validation layer, Embree and TBB for the reference tracer, libstdc++) do through intercepted calls (malloc,
    # free, memcpy) is not checked, as their own memory accesses are not; their locks still order our threads.
    # Why this and not race: suppressions by library: scripts/sanitizers/tsan.supp.
    export TSAN_OPTIONS="halt_on_error=1:second_deadlock_stack=1:ignore_noninstrumented_modules=1:suppressions=$supp/tsan.supp:print_suppressions=0:log_path=$reports"
    export LD_PRELOAD="$root/build-tsan/keep_loaded.so"
    run "raybridge_tests [threads]" build-tsan/tests/raybridge_tests "[threads]"
  )
  echo "sanitize: tsan runs took $(($(date +%s) - start)) s"
fi
echo "sanitize: $what passed"
