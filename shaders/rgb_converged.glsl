// Converged-tile skipping for the passes with an RGB signal: reflections (ReflectionSettings::schedule.convergedTiles,
// pc.flags has RB_DN_RGB_REFLECTION) and local lights (ManyLightSettings::schedule.convergedTiles), shared by their two
// dispatches, one workgroup per 8x8-pixel tile: rgb_converged.comp before the trace decides which tiles have
// converged and writes their outputs (the ray generation shader then skips them), rgb_converged_check.comp after the
// trace checks the tiles refreshed this frame against their history. Both read the RGB denoiser's latest history
// through its own reprojection (rbDnRgbFindHistory, the temporal pass's test), so a pixel counted as converged is one
// the temporal pass will find the same history for. As shadow_converged.glsl, for a signal that is a colour; a
// reflection also depends on the view (the drift below), diffuse irradiance does not.
#ifndef RAYBRIDGE_RGB_CONVERGED_GLSL
#define RAYBRIDGE_RGB_CONVERGED_GLSL

#include "converged_common.glsl"
#include "denoise_rgb_common.glsl"

layout(set = 0, binding = RB_CONVERGED_BINDING_HISTORY) uniform sampler2D historyIn;  // rgb: mean, a: frames
layout(set = 0, binding = RB_CONVERGED_BINDING_DISTANCE) uniform sampler2D surfaceIn;  // distance, frame variance
layout(set = 0, binding = RB_CONVERGED_BINDING_ROUGHNESS) uniform sampler2D gRoughness;

struct ConvergedRgb {
  bool inside;     // in the image
  bool covered;    // the pass traces rays there: a surface (reflections: under the roughness threshold)
  bool mirror;     // reflections: so smooth that it traces one ray (ReflectionPass: roughness under 0.02)
  bool history;    // the temporal pass will find history for it
  vec3 mean;       // that history's mean colour
  float frames;    // the frames it holds
  float variance;  // the variance of one frame's colour there (the sum of the three channels')
  float drift;     // reflections: how far the view turned since last frame, in widths of the pixel's glossy lobe
};

// The width, in radians, that a change of view direction is measured against: the reflected lobe of GGX roughness
// r spreads over about 2 r^2 around the mirror direction. Floored so that a mirror (1 ray, no lobe) is not a
// division by zero: it then counts any turn of more than a few thousandths of a radian as a whole lobe's drift.
float rbLobeWidth(float roughness) { return max(2.0 * roughness * roughness, 2e-3); }

bool rbConvergedReflection() { return (pc.flags & RB_DN_RGB_REFLECTION) != 0u; }

ConvergedRgb rbConvergedRgb(uvec2 pixel) {
  ConvergedRgb c;
  c.inside = all(lessThan(pixel, pc.size));
  c.covered = false;
  c.mirror = false;
  c.history = false;
  c.mean = vec3(0.0);
  c.frames = 0.0;
  c.variance = 0.0;
  c.drift = 0.0;
  if (!c.inside) return c;
  ivec2 ip = ivec2(pixel);
  float depth = texelFetch(gDepth, ip, 0).r;
  if (rbDnSky(depth)) return c;
  float roughness = 1.0;
  if (rbConvergedReflection()) {
    vec4 r = texelFetch(gRoughness, ip, 0);
    roughness = (pc.flags & RB_DN_RGB_ROUGHNESS_IMAGE) != 0u ? r.x : r.w;
    if (roughness > pc.roughnessThreshold) return c;
    c.mirror = roughness < 0.02;
  }
  c.covered = true;
  vec3 rel = rbDnCameraRelative(pixel, depth);
  vec4 h;
  c.history = rbDnRgbFindHistory(pixel, rel, gMotion, gReactive, historyIn, surfaceIn, h, c.variance);
  if (c.history) {
    c.mean = h.rgb;
    c.frames = floor(h.a + 0.5);
  }
  if (!rbConvergedReflection()) return c;
  // A reflection depends on where it is seen from: the angle between the directions from the point to this
  // frame's camera and to last frame's (a rotation of the camera alone turns neither).
  vec3 now = normalize(rel), before = normalize(rel + pc.cameraDelta);
  float turned = atan(length(cross(now, before)), max(dot(now, before), -1.0));
  c.drift = turned / rbLobeWidth(roughness);
  return c;
}

#endif
