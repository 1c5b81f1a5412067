#version 460
#extension GL_GOOGLE_include_directive : require
// Temporal accumulation with reprojection: each pixel finds where its surface was last frame (camera motion,
// or the engine's motion vectors), reads the history there bilinearly from the texels that hold the same surface
// (view distance within a tolerance), and blends its new noisy value into the history as a running mean over up to
// `max history` frames, fewer where the history disagrees with this frame's neighbourhood by more than its noise
// (anti-lag, rbDnHistoryTrust).
// It also measures the noise left in that mean (denoise_noise.glsl), which the a-trous steps filter by: .g of
// the value written is its variance.
#include "denoise_noise.glsl"

layout(local_size_x = 8, local_size_y = 8) in;
layout(set = 0, binding = RB_TEMPORAL_BINDING_DEPTH) uniform sampler2D gDepth;
layout(set = 0, binding = RB_TEMPORAL_BINDING_MOTION) uniform sampler2D gMotion;  // pixels, current - previous
layout(set = 0, binding = RB_TEMPORAL_BINDING_REACTIVE) uniform sampler2D gReactive;
layout(set = 0, binding = RB_TEMPORAL_BINDING_SIGNAL) uniform sampler2D signalIn;        // this frame's noisy value
layout(set = 0, binding = RB_TEMPORAL_BINDING_HISTORY_IN) uniform sampler2D historyIn;   // x: value, y: frames
layout(set = 0, binding = RB_TEMPORAL_BINDING_DISTANCE_IN) uniform sampler2D distanceIn; // last frame's distance
layout(set = 0, binding = RB_TEMPORAL_BINDING_HISTORY_OUT, rg16f) uniform writeonly image2D historyOut;
layout(set = 0, binding = RB_TEMPORAL_BINDING_DISTANCE_OUT, r16f) uniform writeonly image2D distanceOut;
layout(set = 0, binding = RB_TEMPORAL_BINDING_VALUE_OUT, rg16f) uniform writeonly image2D valueOut;
layout(set = 0, binding = RB_TEMPORAL_BINDING_FINAL_OUT, r16f) uniform writeonly image2D finalOut;

void main() {
  uvec2 pixel = gl_GlobalInvocationID.xy;
  if (any(greaterThanEqual(pixel, pc.size))) return;
  ivec2 ip = ivec2(pixel);
  const bool final = (pc.flags & RB_DN_TEMPORAL_FINAL) != 0u;
  const float raw = texelFetch(signalIn, ip, 0).r;
  // A pixel of a converged shadow tile that was not traced this frame (a kept-history mark) adds no frame: its
  // history moves to where its surface now is, unchanged. Its mark carries that same reprojected mean, the value
  // it falls back to should the history be gone.
  const bool kept = rbDnKeptMark(raw);
  float value = rbDnSignalValue(raw);
  float depth = texelFetch(gDepth, ip, 0).r;
  if (rbDnSky(depth)) {
    imageStore(historyOut, ip, vec4(value, 0.0, 0.0, 0.0));
    imageStore(distanceOut, ip, vec4(0.0));
    imageStore(valueOut, ip, vec4(value, 0.0, 0.0, 0.0));
    if (final) imageStore(finalOut, ip, vec4(value));
    return;
  }
  vec3 rel = rbDnCameraRelative(pixel, depth);
  float dist = length(rel);
  imageStore(distanceOut, ip, vec4(dist));
  float accumulated = value;
  // A pixel whose history the reactive mask restarts, or follows up (rbDnFollowUp), traced RaySchedule::resetRays rays
  // (reset_rays.glsl): its value counts as that many frames of the usual rays, so the frames after it weigh in by
  // their rays; so where it finds no history (a follow-up pixel newly visible, RB_CHANGE_REVEALS).
  const bool followUp = !kept && rbDnFollowUp(pixel, gReactive);
  float frames = rbDnReactive(pixel, gReactive) || followUp ? min(pc.resetFrames, float(pc.maxHistoryFrames)) : 1.0;
  ivec2 pp;
  vec2 h;
  if (rbDnFindHistoryBilinear(pixel, rel, gMotion, gReactive, distanceIn, historyIn, h, pp)) {
    // Anti-lag: a pixel not traced this frame brings nothing to compare against.
    if (!kept && (pc.flags & RB_DN_ANTI_LAG) != 0u)
      h.y = floor(h.y * rbDnHistoryTrust(signalIn, gDepth, ip, historyIn, pp));
    // A follow-up pixel traced the reset rays again: its value adds that many frames (the same weighing by rays).
    const float added = kept ? 0.0 : followUp ? max(pc.resetFrames, 1.0) : 1.0;
    frames = min(kept ? max(h.y, 1.0) : h.y + added, float(pc.maxHistoryFrames));
    accumulated = kept ? h.x : mix(h.x, value, min(added / frames, 1.0));
  }
  imageStore(historyOut, ip, vec4(accumulated, frames, 0.0, 0.0));
  imageStore(valueOut, ip, vec4(accumulated, rbDnNoiseVariance(signalIn, ip, accumulated, frames), 0.0, 0.0));
  if (final) imageStore(finalOut, ip, vec4(accumulated));
}
