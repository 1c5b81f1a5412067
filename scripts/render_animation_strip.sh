#!/usr/bin/env bash
# Renders the demo scene with three skinned characters (raybridge-render --characters 3: CesiumMan, Fox,
# BrainStem from ../shared/scenes) at several --time values (hybrid, preset high) and joins the frames into one
# strip: the README's picture of animated characters.
#   scripts/render_animation_strip.sh [OUT.png] [TIMES...]
# Default: docs/images/animation_strip.png, times 0 0.25 0.5 0.75. Needs a build (scripts/build.sh) and
# python3-pil (Debian) for the joining.
set -euo pipefail
cd "$(dirname "$0")/.."
out="${1:-docs/images/animation_strip.png}"
shift $(( $# > 1 ? 1 : $# ))
times=("$@")
[ ${#times[@]} -gt 0 ] || times=(0 0.25 0.5 0.75)
dir="$(mktemp -d)"
frames=()
for t in "${times[@]}"; do
  ./build/tools/render/raybridge-render --characters 3 --time "$t" --fps 30 --frames 4 --preset high \
    --width 360 --height 300 --camera 0.3,1.7,10.6,0,0.75,5.4,32 --out "$dir/$t" >/dev/null
  frames+=("$dir/$t/final.png")
done
/usr/bin/python3 - "$out" "${frames[@]}" <<'PY'
import sys
from PIL import Image
out, paths = sys.argv[1], sys.argv[2:]
images = [Image.open(p).convert("RGB") for p in paths]
w, h = images[0].size
strip = Image.new("RGB", (w * len(images), h))
for i, im in enumerate(images):
    strip.paste(im, (i * w, 0))
strip.save(out, optimize=True)
print("wrote", out, strip.size)
PY
rm -rf "$dir"
