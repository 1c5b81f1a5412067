#version 460
#extension GL_GOOGLE_include_directive : require
// Adaptive rays, step 2 of 2: each pixel's rays this frame. The frame's budget R (pc.uniformRays per surface pixel
// when set, never above pc.budget) first gives every surface pixel pc.minRays; the rest is shared in proportion to
// the weights of adaptive_estimate.comp, rounded stochastically (unbiased: the expected total is R) and capped at pc.maxRays.
// Then each workgroup claims its rays from the frame's counter with one atomic, and a pixel gets only what is
// left under R: the rays traced never exceed the budget, whatever the rounding did. Writes the plan
// (rays, history mean) the ray generation shader reads.
#define RB_ADAPTIVE_PLANNING
#include "adaptive_rays.glsl"
#include "raybridge_pass_constants.glsl"
#include "raybridge_sampling.glsl"

layout(local_size_x = 8, local_size_y = 8) in;
layout(push_constant) uniform AdaptivePushConstants { AdaptivePlanConstants pc; };
layout(set = 0, binding = RB_ADAPTIVE_BINDING_WEIGHTS, rg16f) uniform readonly image2D weightsIn;
layout(set = 0, binding = RB_ADAPTIVE_BINDING_PLAN, rg16f) uniform writeonly image2D planOut;

shared uint scan[64];
shared uint groupBase;

void main() {
  uvec2 pixel = gl_GlobalInvocationID.xy;
  uint lane = gl_LocalInvocationIndex;
  const float surface = float(counters.surfacePixels);
  const float budget = pc.uniformRays > 0.0 ? min(pc.uniformRays * surface, float(pc.budget)) : float(pc.budget);
  const bool inside = all(lessThan(pixel, pc.size));
  vec2 wv = inside ? imageLoad(weightsIn, ivec2(pixel)).xy : vec2(1.0, 0.0);
  uint rays = 0u;
  if (wv.y > 0.0) {  // a surface pixel (sky weighs exactly 0)
    float u = rbToUnit(rbPcg(pixel.x + pc.size.x * pixel.y + rbPcg(pc.frameIndex ^ 0x5bd1e995u)));
    float floorRays = float(min(pc.minRays, pc.maxRays));
    float share;
    if (budget >= floorRays * surface) {
      float total = rbAdaptiveWeightTotal(pc.size);
      float extra = budget - floorRays * surface;
      share = floorRays + (total > 0.0 ? extra * wv.y / total : 0.0);
    } else {
      share = budget / surface;  // not even the minimum everywhere: spread what there is evenly
    }
    rays = min(uint(floor(share + u)), pc.maxRays);
  }
  // Inclusive scan of the workgroup's requests (Hillis-Steele over 64 lanes).
  scan[lane] = rays;
  barrier();
  for (uint offset = 1u; offset < 64u; offset <<= 1u) {
    uint add = lane >= offset ? scan[lane - offset] : 0u;
    barrier();
    scan[lane] += add;
    barrier();
  }
  // In integers, under the cap exactly (a float above 2^24 is rounded, above 2^32 out of range).
  const uint budgetRays = min(uint(min(budget, 4294967040.0)), pc.budget);
  if (lane == 63u) groupBase = rbAdaptiveClaim(scan[63], budgetRays);
  if (gl_WorkGroupID.xy == uvec2(0u) && lane == 0u) counters.budget = budgetRays;
  barrier();
  const uint before = groupBase + scan[lane] - rays;  // rays claimed ahead of this pixel
  const uint granted = before >= budgetRays ? 0u : min(rays, budgetRays - before);
  if (inside) imageStore(planOut, ivec2(pixel), vec4(float(granted), wv.x, 0.0, 0.0));
}
