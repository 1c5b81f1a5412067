#version 460
#extension GL_GOOGLE_include_directive : require
// Temporal accumulation of an RGB signal with reprojection (as denoise_temporal.comp: the same surface found
// where it was last frame, here read bilinearly; a running mean over up to `max history` frames), plus the
// running variance of one frame's colour (Welford's recurrence: no cancellation, so a converged or noise-free
// pixel reads ~0; SVGF, Schied et al. 2017, keeps raw moments instead). Writes the accumulated colour with its
// standard deviation in .a: the variance of one frame (from the history, or from the neighbourhood while the
// history is short) divided by the frames averaged, so the spatial filter knows how noisy the mean still is.
// It also writes the guide image of the a-trous steps. Reflections (RB_DN_RGB_REFLECTION): a pixel without
// coverage is handled like the sky, and the deviation shrinks with the roughness below kRbDnGlossyRoughness, so
// the a-trous steps leave a mirror's sharp reflection as it is. A kept-history mark (RB_DN_KEPT_MARKS: converged
// reflection tiles) adds no frame: the pixel's history is carried to its new position unchanged; a stale mark (a = 2)
// drops the pixel's history.
#include "denoise_rgb_common.glsl"

layout(local_size_x = 8, local_size_y = 8) in;
layout(set = 0, binding = RB_RGB_TEMPORAL_BINDING_DEPTH) uniform sampler2D gDepth;
layout(set = 0, binding = RB_RGB_TEMPORAL_BINDING_MOTION) uniform sampler2D gMotion;  // pixels, current - previous
layout(set = 0, binding = RB_RGB_TEMPORAL_BINDING_REACTIVE) uniform sampler2D gReactive;
layout(set = 0, binding = RB_RGB_TEMPORAL_BINDING_SIGNAL) uniform sampler2D signalIn;  // .rgb, this frame's
layout(set = 0, binding = RB_RGB_TEMPORAL_BINDING_HISTORY_IN) uniform sampler2D historyIn;
layout(set = 0, binding = RB_RGB_TEMPORAL_BINDING_SURFACE_IN) uniform sampler2D surfaceIn;
layout(set = 0, binding = RB_RGB_TEMPORAL_BINDING_HISTORY_OUT, rgba16f) uniform writeonly image2D historyOut;
layout(set = 0, binding = RB_RGB_TEMPORAL_BINDING_SURFACE_OUT, rg16f) uniform writeonly image2D surfaceOut;
layout(set = 0, binding = RB_RGB_TEMPORAL_BINDING_VALUE_OUT, rgba16f) uniform writeonly image2D valueOut;
layout(set = 0, binding = RB_RGB_TEMPORAL_BINDING_GUIDE_OUT, rg32ui) uniform writeonly uimage2D guideOut;
layout(set = 0, binding = RB_RGB_TEMPORAL_BINDING_NORMAL) uniform sampler2D gNormal;
layout(set = 0, binding = RB_RGB_TEMPORAL_BINDING_ROUGHNESS) uniform sampler2D gRoughness;

// Reflections: the roughness from which the filter treats a reflection as glossy (noisy) in full; a mirror's
// (ReflectionPass traces one deterministic ray under 0.02) spread over its neighbours is detail, not noise.
const float kRbDnGlossyRoughness = 0.1;

float squared(vec3 v) { return dot(v, v); }

// One frame's variance from the neighbourhood: the least of the four 3x3 windows that have this pixel in a
// corner (Kuwahara's trick). Noise spreads every window, while a noise-free edge leaves at least one window on
// its own side, so it is not taken for noise. Neighbours on another surface (a depth step) are left out.
// Each window fetches its own 9 texels (the shared ones again, from the cache) instead of the 5x5 block being
// held: 25 colours and flags live at once would size every thread of this pass by this rarely taken branch.
float spatialVariance(ivec2 ip, float dist) {
  float least = 1e30;
  for (int wy = 0; wy <= 2; wy += 2) {
    for (int wx = 0; wx <= 2; wx += 2) {
      vec3 m1 = vec3(0.0), gx = vec3(0.0), gy = vec3(0.0);
      float m2 = 0.0, count = 0.0;
      for (int y = 0; y < 3; ++y) {
        for (int x = 0; x < 3; ++x) {
          ivec2 q = clamp(ip + ivec2(wx + x - 2, wy + y - 2), ivec2(0), ivec2(pc.size) - 1);
          float qd = texelFetch(gDepth, q, 0).r;
          vec4 qv = texelFetch(signalIn, q, 0);
          bool same = !rbDnSky(qd) && abs(length(rbDnCameraRelative(uvec2(q), qd)) - dist) <= 0.05 * dist &&
                      ((pc.flags & RB_DN_RGB_REFLECTION) == 0u || qv.a >= 0.5 || rbDnRgbKeptMark(qv.a));
          if (!same) continue;
          vec3 c = qv.rgb;
          m1 += c;
          m2 += squared(c);
          gx += float(x - 1) * c;
          gy += float(y - 1) * c;
          count += 1.0;
        }
      }
      // count >= 1: the centre is in every window and always on its own surface. A whole window also loses
      // its plane (mean and two slopes, orthogonal over the 3x3 grid), so a smooth gradient is not noise
      // either; 6 degrees of freedom remain.
      float v = count == 9.0 ? max(m2 - squared(m1) / 9.0 - squared(gx) / 6.0 - squared(gy) / 6.0, 0.0) / 6.0
                             : max(m2 - squared(m1) / count, 0.0) / max(count - 1.0, 1.0);
      least = min(least, v);
    }
  }
  return least;
}

void main() {
  uvec2 pixel = gl_GlobalInvocationID.xy;
  if (any(greaterThanEqual(pixel, pc.size))) return;
  ivec2 ip = ivec2(pixel);
  const bool final = (pc.flags & RB_DN_RGB_FINAL) != 0u;
  const bool reflection = (pc.flags & RB_DN_RGB_REFLECTION) != 0u;
  vec4 texel = texelFetch(signalIn, ip, 0);
  vec3 value = texel.rgb;
  const bool kept = rbDnRgbKeptMark(texel.a);
  float depth = texelFetch(gDepth, ip, 0).r;
  if (rbDnSky(depth) || (reflection && texel.a < 0.5 && !kept)) {
    imageStore(historyOut, ip, vec4(value, 0.0));
    imageStore(surfaceOut, ip, vec4(0.0));
    imageStore(valueOut, ip, vec4(value, final ? (reflection ? 0.0 : 1.0) : 0.0));
    imageStore(guideOut, ip, uvec4(0u));
    return;
  }
  vec3 rel = rbDnCameraRelative(pixel, depth);
  float dist = length(rel);
  imageStore(guideOut, ip, uvec4(rbDnPackGuide(dist, rbDnNormal(texelFetch(gNormal, ip, 0))), 0u, 0u));
  vec3 accumulated = value;
  float variance = 0.0;  // of one frame's colour, over the frames accumulated
  float frames = 1.0;
  vec4 h;
  float v;
  ivec2 pp;
  if (!rbDnRgbStaleMark(texel.a) &&
      rbDnRgbFindHistory(pixel, rel, gMotion, gReactive, historyIn, surfaceIn, h, v, pp)) {
    if (kept) {
      // Not traced this frame: the history as it was, no frame added (the mark's rgb is this same mean).
      frames = clamp(floor(h.a + 0.5), 1.0, float(pc.maxHistoryFrames));
      accumulated = h.rgb;
      variance = v;
    } else {
      float previous = floor(h.a + 0.5);  // frames the history holds
      if ((pc.flags & RB_DN_ANTI_LAG) != 0u)
        previous = floor(previous * rbDnRgbHistoryTrust(ip, pp, gDepth, signalIn, historyIn, surfaceIn));
      frames = min(previous + 1.0, float(pc.maxHistoryFrames));
      float alpha = 1.0 / frames;
      accumulated = mix(h.rgb, value, alpha);
      variance = (1.0 - alpha) * (v + alpha * squared(value - h.rgb));
    }
  }
  imageStore(historyOut, ip, vec4(accumulated, frames));
  imageStore(surfaceOut, ip, rbDnRgbSurfaceTexel(dist, variance));
  // Too few frames for the recurrence to know the noise: the neighbourhood's.
  float frameVariance = frames < kRbDnMinTemporalVarianceFrames ? spatialVariance(ip, dist) : variance;
  float deviation = sqrt(frameVariance / frames);
  if (reflection) {
    float roughness = (pc.flags & RB_DN_RGB_ROUGHNESS_IMAGE) != 0u ? texelFetch(gRoughness, ip, 0).x
                                                                   : texelFetch(gRoughness, ip, 0).w;
    deviation *= clamp(roughness / kRbDnGlossyRoughness, 0.0, 1.0);
  }
  imageStore(valueOut, ip, vec4(accumulated, final ? 1.0 : deviation));
}
