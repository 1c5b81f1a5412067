#version 460
#extension GL_GOOGLE_include_directive : require
// Adaptive rays, step 1 of 2: how much each pixel would gain from rays this frame. It reprojects the denoiser's
// history of the signal (its running mean p over f frames, exactly as the temporal pass will) and weighs the pixel
// by the variance its mean still has: p (1 - p) / f, the binomial variance of one ray's 0/1 result (an upper bound
// for any [0, 1] estimator) shared by the frames already accumulated. A pixel without history (disoccluded, new)
// counts as kNoHistoryFrames frames of p = 0.5, the most uncertain. Writes (p, weight) per pixel and adds the
// weights and the surface pixels into the plan's counters (adaptive_rays.glsl); sky pixels weigh nothing.
#define RB_ADAPTIVE_PLANNING
#include "adaptive_rays.glsl"
#include "denoise_common.glsl"

layout(local_size_x = 8, local_size_y = 8) in;
layout(set = 0, binding = RB_ADAPTIVE_BINDING_DEPTH) uniform sampler2D gDepth;
layout(set = 0, binding = RB_ADAPTIVE_BINDING_MOTION) uniform sampler2D gMotion;  // pixels, current - previous
layout(set = 0, binding = RB_ADAPTIVE_BINDING_REACTIVE) uniform sampler2D gReactive;
layout(set = 0, binding = RB_ADAPTIVE_BINDING_HISTORY) uniform sampler2D historyIn;    // x: mean, y: frames
layout(set = 0, binding = RB_ADAPTIVE_BINDING_DISTANCE) uniform sampler2D distanceIn;  // last frame's distance
layout(set = 0, binding = RB_ADAPTIVE_BINDING_WEIGHTS, rg16f) uniform writeonly image2D weightsOut;

// Variance floor: a converged pixel still draws a few rays, so that a change the history has not seen yet
// (a moving light, a new occluder) is found.
const float kVarianceFloor = 0.01;
const float kNoHistoryFrames = 0.5;

shared float groupWeight[64];
shared uint groupSurface[64];

void main() {
  uvec2 pixel = gl_GlobalInvocationID.xy;
  uint lane = gl_LocalInvocationIndex;
  float weight = 0.0;
  uint surface = 0u;
  if (all(lessThan(pixel, pc.size))) {
    ivec2 ip = ivec2(pixel);
    float depth = texelFetch(gDepth, ip, 0).r;
    float mean = 1.0;
    if (!rbDnSky(depth)) {
      mean = 0.5;
      float frames = kNoHistoryFrames;
      ivec2 pp;
      // The same reprojection and surface test as the denoiser's temporal pass.
      if (rbDnFindHistory(pixel, rbDnCameraRelative(pixel, depth), gMotion, gReactive, distanceIn, pp)) {
        vec2 h = texelFetch(historyIn, pp, 0).xy;
        mean = clamp(h.x, 0.0, 1.0);
        frames = max(h.y, 1.0);
      }
      weight = (mean * (1.0 - mean) + kVarianceFloor) / frames;
      surface = 1u;
    }
    imageStore(weightsOut, ip, vec4(mean, weight, 0.0, 0.0));
  }
  // One atomic per workgroup: the weights summed in float first, so that small weights are not lost to the
  // fixed point of the global sum.
  groupWeight[lane] = weight;
  groupSurface[lane] = surface;
  barrier();
  for (uint stride = 32u; stride > 0u; stride >>= 1u) {
    if (lane < stride) {
      groupWeight[lane] += groupWeight[lane + stride];
      groupSurface[lane] += groupSurface[lane + stride];
    }
    barrier();
  }
  if (lane == 0u) {
    atomicAdd(counters.weightSum, uint(round(groupWeight[0] * float(rbAdaptiveWeightScale(pc.size)))));
    atomicAdd(counters.surfacePixels, groupSurface[0]);
  }
}
