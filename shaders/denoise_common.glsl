// Shared by the denoiser's compute shaders: push constants and G-buffer reconstruction.
#ifndef RAYBRIDGE_DENOISE_COMMON_GLSL
#define RAYBRIDGE_DENOISE_COMMON_GLSL

#include "raybridge_gbuffer.glsl"

#include "raybridge_pass_constants.glsl"
// A shader whose push constants embed the DenoiseConstants (shadow_converged.glsl) declares its own block and
// defines pc as the embedded struct first.
#ifndef RB_DN_PUSH_CONSTANTS_DECLARED
layout(push_constant) uniform DenoisePushConstants { DenoiseConstants pc; };
#endif

bool rbDnSky(float depth) { return (pc.flags & RB_DN_REVERSED_Z) != 0u ? depth <= 0.0 : depth >= 1.0; }

vec3 rbDnCameraRelative(uvec2 pixel, float depth) {
  return rbReconstructCameraRelative(pixel, vec2(pc.size), depth, pc.inverseProjection, pc.viewToWorld,
                                     pc.wAtDepthOne, (pc.flags & RB_DN_REVERSED_Z) != 0u);
}

// The view-space position: what the a-trous taps compare (against the centre's normal turned into view space),
// which saves each tap the rotation into world axes.
vec3 rbDnViewPosition(uvec2 pixel, float depth) {
  return rbReconstructViewPosition(pixel, vec2(pc.size), depth, pc.inverseProjection, pc.wAtDepthOne,
                                   (pc.flags & RB_DN_REVERSED_Z) != 0u);
}

// Where the surface at `pixel` (camera-relative position `rel`) was in last frame's image, in pixels (continuous:
// texel centres at .5): by the G-buffer's motion vectors where it has them, else by last frame's camera. `prevRel`:
// the point relative to last frame's camera.
vec2 rbDnPreviousPixel(uvec2 pixel, vec3 rel, sampler2D motion, out vec3 prevRel) {
  prevRel = rel + pc.cameraDelta;
  if ((pc.flags & RB_DN_MOTION) != 0u) {
    vec2 m = texelFetch(motion, ivec2(pixel), 0).xy;
    // A NaN or infinite motion vector (an engine bug, a division by w = 0) has no previous pixel: off screen, so the
    // pixel starts afresh instead of reading a history texel chosen by undefined float-to-int conversion.
    if (any(isnan(m)) || any(isinf(m))) return vec2(-1e9);
    return vec2(pixel) + 0.5 - m;
  }
  vec4 clip = pc.previousViewProjection * vec4(prevRel, 1.0);
  return (clip.xy / clip.w * 0.5 + 0.5) * vec2(pc.size);
}

// The engine's reactive mask drops this pixel's history (RB_DN_REACTIVE: .r > 0.5; particles, UI, anything the
// SDK does not see change).
bool rbDnReactive(uvec2 pixel, sampler2D reactive) {
  return (pc.flags & RB_DN_REACTIVE) != 0u && texelFetch(reactive, ivec2(pixel), 0).r > RB_REACTIVE_RESTART;
}

// A follow-up pixel: its history restarted in one of the last frames, and it traced the reset rays again this frame
// (RB_REACTIVE_FOLLOW_UP < .r <= RB_REACTIVE_RESTART; reset_rays.glsl). It keeps its history.
bool rbDnFollowUp(uvec2 pixel, sampler2D reactive) {
  if ((pc.flags & RB_DN_REACTIVE) == 0u) return false;
  const float r = texelFetch(reactive, ivec2(pixel), 0).r;
  return r > RB_REACTIVE_FOLLOW_UP && r <= RB_REACTIVE_RESTART;
}

// Where the surface at `pixel` (camera-relative position `rel`) was in the latest history: `pp`, that history's
// texel, and whether the same surface is there (its distance from last frame's camera matches what was stored) and
// the engine did not mark the pixel reactive. The temporal pass's test, shared with the readers of its history that
// must agree with it (converged shadow tiles: a pixel they skip is one the temporal pass finds history for).
bool rbDnFindHistory(uvec2 pixel, vec3 rel, sampler2D motion, sampler2D reactive, sampler2D distanceIn,
                     out ivec2 pp) {
  vec3 prevRel;
  vec2 prevPixel = rbDnPreviousPixel(pixel, rel, motion, prevRel);
  pp = ivec2(floor(prevPixel));
  if ((pc.flags & RB_DN_HISTORY) == 0u || rbDnReactive(pixel, reactive) || any(lessThan(pp, ivec2(0))) ||
      any(greaterThanEqual(pp, ivec2(pc.size)))) {
    return false;
  }
  float prevDist = texelFetch(distanceIn, pp, 0).r;
  return prevDist > 0.0 && abs(prevDist - length(prevRel)) <= 0.02 * length(prevRel) + 1e-3;
}

// The bilinear footprint of a reprojected point in last frame's history (both temporal passes): the four texels
// around `prevPixel` (continuous, texel centres at .5) from `base`, texel k at base + (k & 1, k >> 1), weighted
// bilinearly where the texel holds the same surface (its stored view distance, .x of `distanceIn`, within 2% of
// `expected`, rbDnFindHistory's test) and 0 elsewhere, outside the image too. Returns the weights' sum: about 0 when no
// texel holds the surface. Nearest-texel reads drift: a camera that moves 0.3 px a frame rounds to the same texel
// every frame, so the history stays behind the image (the motion bench's pan and turn: denoised shadows dragged
// several pixels, 3x the raw error).
float rbDnBilinearSameSurface(vec2 prevPixel, float expected, sampler2D distanceIn, out ivec2 base, out vec4 w) {
  vec2 f = prevPixel - 0.5;
  base = ivec2(floor(f));
  vec2 t = f - vec2(base);
  float sum = 0.0;
  for (int k = 0; k < 4; ++k) {
    ivec2 o = ivec2(k & 1, k >> 1);
    ivec2 q = base + o;
    w[k] = 0.0;
    if (any(lessThan(q, ivec2(0))) || any(greaterThanEqual(q, ivec2(pc.size)))) continue;
    float prevDist = texelFetch(distanceIn, q, 0).x;
    if (!(prevDist > 0.0 && abs(prevDist - expected) <= 0.02 * expected + 1e-3)) continue;
    w[k] = (o.x == 1 ? t.x : 1.0 - t.x) * (o.y == 1 ? t.y : 1.0 - t.y);
    sum += w[k];
  }
  return sum;
}

// The scalar temporal pass's own read of the history: rbDnFindHistory's test texel by texel, over the bilinear
// footprint (rbDnBilinearSameSurface). Returns whether any texel holds the surface: then `h` is (mean, frames) and
// `pp` the nearest texel (rbDnFindHistory's, the anti-lag window's centre).
bool rbDnFindHistoryBilinear(uvec2 pixel, vec3 rel, sampler2D motion, sampler2D reactive, sampler2D distanceIn,
                             sampler2D historyIn, out vec2 h, out ivec2 pp) {
  h = vec2(0.0);
  vec3 prevRel;
  vec2 prevPixel = rbDnPreviousPixel(pixel, rel, motion, prevRel);
  pp = ivec2(floor(prevPixel));
  if ((pc.flags & RB_DN_HISTORY) == 0u || rbDnReactive(pixel, reactive)) return false;
  ivec2 base;
  vec4 w;
  float weights = rbDnBilinearSameSurface(prevPixel, length(prevRel), distanceIn, base, w);
  if (weights <= 1e-3) return false;
  for (int k = 0; k < 4; ++k)
    if (w[k] > 0.0) h += w[k] * texelFetch(historyIn, base + ivec2(k & 1, k >> 1), 0).xy;
  h /= weights;
  h.y = floor(h.y + 0.5);
  return true;
}

// A scalar signal's value: a kept-history mark (RB_DN_KEPT_MARKS, -1 - v) read as the v it carries.
float rbDnSignalValue(float v) { return (pc.flags & RB_DN_KEPT_MARKS) != 0u && v < -0.5 ? -1.0 - v : v; }
bool rbDnKeptMark(float v) { return (pc.flags & RB_DN_KEPT_MARKS) != 0u && v < -0.5; }

// Anti-lag (RB_DN_ANTI_LAG): the history is trusted in full while its 3x3 neighbourhood mean differs from this
// frame's by under kRbDnLagSigmasLow standard deviations of that difference's noise, not at all from
// kRbDnLagSigmasHigh on, linearly between. Comparing means over the same footprint, not the pixel alone, is what
// makes one-ray signals usable: a single binary ray says nothing, nine of them against a converged history do. The
// low end sits above the noise (a still scene keeps its history: flicker unchanged on the motion tests), and the
// ramp is short because a history kept in part keeps its stale value in part (tests/motion_lag_test.cpp, AO at 4
// rays two frames after a teleport: 2.7x the still error with a 2.5 to 5 ramp, 1.8x with 3 to 3.5). A full-contrast
// change of the mean is 6 sigmas at one ray and p = 0.5, 12 at four rays.
const float kRbDnLagSigmasLow = 3.0;
const float kRbDnLagSigmasHigh = 3.5;

float rbDnLagTrust(float z, float low, float high) { return clamp((high - z) / (high - low), 0.0, 1.0); }

vec3 rbDnNormal(vec4 texel) { return rbDecodeNormal(texel, (pc.flags & RB_DN_OCTAHEDRAL) != 0u ? 1u : 0u); }

#endif
