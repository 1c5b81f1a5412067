#version 460
#extension GL_GOOGLE_include_directive : require
// Converged-tile skipping for RGB signals (reflections, local lights), step 2 (after the trace): a tile refreshed
// this frame (converged, traced anyway) whose new colour disagrees with its history by more than the noise the
// denoiser measured there has seen a change the history could not (a moved light, or an object moved in a
// reflection): it is held, traced every frame
// for the next tc.minFrames frames, before it may be skipped again. The test: over the tile's covered pixels with
// history, the sum of |new - mean|^2 over the variance of one frame's colour (the sum of the channels', plus a floor
// relative to the colour, so that a noise-free mirror whose reflection changes counts without dividing by zero),
// against a chi-square bound of 3 per pixel plus 32, as for shadows; or any one pixel beyond kPixelBound (4 standard
// deviations), so that a change in a few pixels of a tile (a small object in a mirror) is not diluted by the rest.
// A held tile's history is stale, and the denoiser's running mean would take many frames to forget it: its covered
// pixels get a = 2 instead of 1, which the RGB denoiser (RB_DN_KEPT_MARKS) reads as "traced, start afresh".
#include "rgb_converged.glsl"

// This frame's, traced (GENERAL: read, and a = 2 written where the tile is held).
layout(set = 0, binding = RB_CONVERGED_BINDING_VISIBILITY, rgba16f) uniform image2D radiance;

// The variance floor, relative to the mean colour's magnitude (at least 0.05): a noise-free pixel whose reflection
// changes by a third of its colour weighs about 11.
const float kRelativeFloor = 0.1;

// One pixel's |new - mean|^2 over its variance beyond which the tile is held whatever its other pixels say: 4
// standard deviations. A false alarm costs a held tile's rays and history; 8 (64) missed glossy pixels whose
// reflection had darkened by two thirds (tests/converged_reflection_test.cpp).
const float kPixelBound = 16.0;

shared float deviation[RB_SHADOW_TILE_SIZE * RB_SHADOW_TILE_SIZE];
shared uint pixels;
shared uint outlier;
shared bool held;

void main() {
  uint tile = rbConvergedTile();
  if ((tileState[tile] & RB_TILE_REFRESH) == 0u) return;  // the whole workgroup
  uint lane = gl_LocalInvocationIndex;
  if (lane == 0u) {
    pixels = 0u;
    outlier = 0u;
  }
  barrier();
  uvec2 pixel = gl_GlobalInvocationID.xy;
  ConvergedRgb c = rbConvergedRgb(pixel);
  float d = 0.0;
  vec4 traced = c.covered ? imageLoad(radiance, ivec2(pixel)) : vec4(0.0);
  if (c.covered && c.history) {
    vec3 diff = traced.rgb - c.mean;
    float floorDeviation = kRelativeFloor * max(length(c.mean), 0.05);
    d = dot(diff, diff) / (c.variance + floorDeviation * floorDeviation);
    atomicAdd(pixels, 1u);
    if (d > kPixelBound) outlier = 1u;
  }
  deviation[lane] = d;
  barrier();
  for (uint stride = 32u; stride > 0u; stride >>= 1u) {
    if (lane < stride) deviation[lane] += deviation[lane + stride];
    barrier();
  }
  if (lane == 0u) {
    held = outlier != 0u || deviation[0] > 3.0 * float(pixels) + 32.0;
    if (held) tileState[tile] = (tileState[tile] & ~RB_TILE_HOLD_MASK) | min(tc.minFrames, RB_TILE_HOLD_MASK);
  }
  barrier();
  if (held && c.covered) imageStore(radiance, ivec2(pixel), vec4(traced.rgb, 2.0));
}
