// Converged-tile skipping for the shadow pass (ShadowSettings::schedule.convergedTiles), shared by its two dispatches, one
// workgroup per 8x8-pixel tile of the classifier: shadow_converged.comp before the classifier decides which tiles
// have converged and writes their outputs, shadow_converged_check.comp after the trace checks the tiles refreshed
// this frame against their history. Both read the denoiser's latest history through its own reprojection
// (rbDnFindHistory, the temporal pass's test), so a pixel counted as converged is one the temporal pass will find
// the same history for.
#ifndef RAYBRIDGE_SHADOW_CONVERGED_GLSL
#define RAYBRIDGE_SHADOW_CONVERGED_GLSL

#include "converged_common.glsl"

layout(set = 0, binding = RB_CONVERGED_BINDING_HISTORY) uniform sampler2D historyIn;    // x: mean, y: frames
layout(set = 0, binding = RB_CONVERGED_BINDING_DISTANCE) uniform sampler2D distanceIn;  // last frame's distance

struct ConvergedPixel {
  bool inside;   // in the image
  bool surface;  // not sky
  bool history;  // the temporal pass will find history for it
  float mean;    // that history's mean (1 for sky: what the pass writes there)
  float frames;  // and the frames it holds
  ivec2 texel;   // where in the history
};

ConvergedPixel rbConvergedPixel(uvec2 pixel) {
  ConvergedPixel c;
  c.inside = all(lessThan(pixel, pc.size));
  c.surface = false;
  c.history = false;
  c.mean = 1.0;
  c.frames = 0.0;
  c.texel = ivec2(0);
  if (!c.inside) return c;
  float depth = texelFetch(gDepth, ivec2(pixel), 0).r;
  if (rbDnSky(depth)) return c;
  c.surface = true;
  c.history = rbDnFindHistory(pixel, rbDnCameraRelative(pixel, depth), gMotion, gReactive, distanceIn, c.texel);
  if (c.history) {
    vec2 h = texelFetch(historyIn, c.texel, 0).xy;
    c.mean = h.x;
    c.frames = h.y;
  }
  return c;
}

#endif
