#version 460
#extension GL_GOOGLE_include_directive : require
// Temporal accumulation with reprojection: each pixel finds where its surface was last frame (camera motion,
// or the engine's motion vectors), checks that the same surface is there (view distance within a tolerance),
// and blends its new noisy value into the history as a running mean over up to `max history` frames.
#include "denoise_common.glsl"

layout(local_size_x = 8, local_size_y = 8) in;
layout(set = 0, binding = 0) uniform sampler2D gDepth;
layout(set = 0, binding = 1) uniform sampler2D gMotion;        // pixels, current - previous (optional)
layout(set = 0, binding = 2) uniform sampler2D signalIn;       // this frame's noisy value
layout(set = 0, binding = 3) uniform sampler2D historyIn;      // x: accumulated value, y: frames accumulated
layout(set = 0, binding = 4) uniform sampler2D distanceIn;     // previous frame's view distance
layout(set = 0, binding = 5, rg16f) uniform writeonly image2D historyOut;
layout(set = 0, binding = 6, r32f) uniform writeonly image2D distanceOut;
layout(set = 0, binding = 7, r16f) uniform writeonly image2D valueOut;  // the accumulated value alone

void main() {
  uvec2 pixel = gl_GlobalInvocationID.xy;
  if (any(greaterThanEqual(pixel, pc.size.xy))) return;
  ivec2 ip = ivec2(pixel);
  float value = texelFetch(signalIn, ip, 0).r;
  float depth = texelFetch(gDepth, ip, 0).r;
  if (rbDnSky(depth)) {
    imageStore(historyOut, ip, vec4(value, 0.0, 0.0, 0.0));
    imageStore(distanceOut, ip, vec4(0.0));
    imageStore(valueOut, ip, vec4(value));
    return;
  }
  vec3 rel = rbDnCameraRelative(pixel, depth);
  float dist = length(rel);
  imageStore(distanceOut, ip, vec4(dist));
  vec2 prevPixel;
  vec3 prevRel = rel + pc.cameraDelta.xyz;
  if ((pc.size.z & RB_DN_MOTION) != 0u) {
    prevPixel = vec2(pixel) + 0.5 - texelFetch(gMotion, ip, 0).xy;
  } else {
    vec4 clip = pc.previousViewProjection * vec4(prevRel, 1.0);
    prevPixel = (clip.xy / clip.w * 0.5 + 0.5) * vec2(pc.size.xy);
  }
  float accumulated = value;
  float frames = 1.0;
  ivec2 pp = ivec2(floor(prevPixel));
  if ((pc.size.z & RB_DN_HISTORY) != 0u && all(greaterThanEqual(pp, ivec2(0))) && all(lessThan(pp, ivec2(pc.size.xy)))) {
    float prevDist = texelFetch(distanceIn, pp, 0).r;
    // The same surface: its distance from last frame's camera matches what was stored there.
    if (prevDist > 0.0 && abs(prevDist - length(prevRel)) <= 0.02 * length(prevRel) + 1e-3) {
      vec2 h = texelFetch(historyIn, pp, 0).xy;
      frames = min(h.y + 1.0, float(pc.size.w));
      accumulated = mix(h.x, value, 1.0 / frames);
    }
  }
  imageStore(historyOut, ip, vec4(accumulated, frames, 0.0, 0.0));
  imageStore(valueOut, ip, vec4(accumulated));
}
