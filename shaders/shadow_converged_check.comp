#version 460
#extension GL_GOOGLE_include_directive : require
// Converged-tile skipping, step 2 (after the trace): a tile refreshed this frame (converged, traced anyway) whose
// new visibility disagrees with its history by more than the rays' noise explains has seen a change the history
// could not (a moved light or occluder): it is held, traced every frame for the next tc.minFrames frames, before it
// may be skipped again. The test: over the tile's surface pixels with history, the sum of (new - mean)^2 over the
// binomial variance of tc.denoise.signalRaysPerPixel rays at the mean (plus a floor, so that an exact 0 or 1 that
// flips counts without dividing by zero), against a chi-square bound of 3 per pixel plus 32.
#include "shadow_converged.glsl"

layout(set = 0, binding = RB_CONVERGED_BINDING_VISIBILITY) uniform sampler2D visibility;  // this frame's, traced

// The variance floor: a flip of a noise-free pixel by a whole ray's worth (1/4 at 4 rays) weighs 25.
const float kVarianceFloor = 0.05 * 0.05;

shared float deviation[RB_SHADOW_TILE_SIZE * RB_SHADOW_TILE_SIZE];
shared uint pixels;

void main() {
  uint tile = rbConvergedTile();
  if ((tileState[tile] & RB_TILE_REFRESH) == 0u) return;  // the whole workgroup
  uint lane = gl_LocalInvocationIndex;
  if (lane == 0u) pixels = 0u;
  barrier();
  uvec2 pixel = gl_GlobalInvocationID.xy;
  ConvergedPixel c = rbConvergedPixel(pixel);
  float d = 0.0;
  if (c.history) {
    float m = clamp(c.mean, 0.0, 1.0);
    float v = texelFetch(visibility, ivec2(pixel), 0).r;
    d = (v - m) * (v - m) / (m * (1.0 - m) / max(pc.signalRaysPerPixel, 1.0) + kVarianceFloor);
    atomicAdd(pixels, 1u);
  }
  deviation[lane] = d;
  barrier();
  for (uint stride = 32u; stride > 0u; stride >>= 1u) {
    if (lane < stride) deviation[lane] += deviation[lane + stride];
    barrier();
  }
  if (lane == 0u && deviation[0] > 3.0 * float(pixels) + 32.0) {
    tileState[tile] = (tileState[tile] & ~RB_TILE_HOLD_MASK) | min(tc.minFrames, RB_TILE_HOLD_MASK);
  }
}
