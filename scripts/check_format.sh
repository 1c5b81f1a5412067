#!/usr/bin/env bash
# Checks that the C++ sources follow the checked-in .clang-format (exit 1 naming the files that do not).
#   scripts/check_format.sh          check (what CI runs, from .ci/run)
#   scripts/check_format.sh --fix    format the covered files in place
#   scripts/check_format.sh --list   print the covered files
# Covered: the .cpp and .h files under sdk/, adapters/, tools/, samples/ and tests/ that git tracks (plus new files
# not yet added, unless .gitignore'd, so a --fix before a commit catches them). GLSL (shaders/,
# samples/*/shaders/) is not covered: clang-format reads it as C++ and splits a block's instance name ("} pc;").
# Installs nothing: clang-format comes from scripts/setup.sh. CLANG_FORMAT=... picks another binary.
set -euo pipefail
cd "$(dirname "$0")/.."

covered_files() {
  git ls-files --cached --others --exclude-standard -- \
    'sdk/*.cpp' 'sdk/*.h' 'adapters/*.cpp' 'adapters/*.h' 'tools/*.cpp' 'tools/*.h' 'samples/*.cpp' 'samples/*.h' \
    'tests/*.cpp' 'tests/*.h' |
    sort -u | while IFS= read -r f; do [ -f "$f" ] && printf '%s\n' "$f"; done
}

mode=check
case "${1:-}" in
  "") ;;
  --fix) mode=fix ;;
  --list) covered_files; exit 0 ;;
  -h|--help) sed -n '2,9p' "$0" | sed 's/^# \{0,1\}//'; exit 0 ;;
  *) echo "check_format: unknown option '$1' (use --fix, --list or --help)" >&2; exit 2 ;;
esac

CF="${CLANG_FORMAT:-clang-format}"
if ! command -v "$CF" >/dev/null 2>&1; then
  echo "check_format: '$CF' not found; run scripts/setup.sh (it installs clang-format)" >&2
  exit 2
fi
version="$("$CF" --version)"
case "$version" in
  *"version 14."*) ;;
  *) echo "check_format: warning: .clang-format is tuned for clang-format 14, this is: $version" >&2 ;;
esac

mapfile -t files < <(covered_files)
if [ "${#files[@]}" -eq 0 ]; then
  echo "check_format: no covered files found (is this a git checkout?)" >&2
  exit 2
fi

if [ "$mode" = fix ]; then
  "$CF" -i --style=file "${files[@]}"
  echo "check_format: formatted ${#files[@]} files in place"
  exit 0
fi

bad=()
for f in "${files[@]}"; do
  if ! "$CF" --dry-run --Werror --style=file "$f" >/dev/null 2>&1; then bad+=("$f"); fi
done

if [ "${#bad[@]}" -ne 0 ]; then
  echo "check_format: ${#bad[@]} of ${#files[@]} files are not formatted per .clang-format:" >&2
  printf '  %s\n' "${bad[@]}" >&2
  echo "Fix: scripts/check_format.sh --fix   (see one file's changes: $CF --style=file FILE | diff FILE -)" >&2
  exit 1
fi
echo "check_format: ${#files[@]} files formatted"
