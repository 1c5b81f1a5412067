// Adaptive rays per pixel (sdk/src/schedule/adaptive_rays.h): the counters the two planning dispatches share, and the plan
// the ray generation shaders read.
#ifndef RAYBRIDGE_ADAPTIVE_RAYS_GLSL
#define RAYBRIDGE_ADAPTIVE_RAYS_GLSL

#include "raybridge_shader_interface.glsl"

// Filled with zeros before the first dispatch of each frame.
struct RbPlanCounters {
  uint weightSum;      // sum of the pixels' weights, in units of 1 / rbAdaptiveWeightScale(size)
  uint surfacePixels;  // pixels that are not sky
  uint raysGranted;    // rays handed out so far by the allocation dispatch (never more than the budget)
  uint budget;         // the frame's ray budget, as the allocation dispatch resolved it
};

// The fixed point of RbPlanCounters::weightSum for an image of `size` pixels: as fine as 32 bits allow. A pixel
// weighs at most 0.52 (adaptive_estimate.comp) and each 8x8 workgroup adds its sum times the scale rounded, at most
// (64 x 0.52 + 0.5) x scale < 35 x scale, so the whole sum stays under 4e9 < 2^32 at any size: 221 at 8K,
// 1,984 at 2560x1440, 2^16 (the cap) on small images. A fixed 256 overflowed at 8K, and was coarse where
// converged pixels weigh 1e-4: one workgroup's rounding was then 20% of its weight. Integer arithmetic: the
// estimate and the allocation dispatches must agree on it exactly.
uint rbAdaptiveWeightScale(uvec2 size) {
  const uint groups = ((size.x + 7u) / 8u) * ((size.y + 7u) / 8u);
  return clamp(4000000000u / max(groups * 35u, 1u), 1u, 65536u);
}

#ifdef RB_ADAPTIVE_PLANNING
// The planning dispatches' counters. Coherent: the claim reads raysGranted as other workgroups move it.
layout(set = 0, binding = RB_ADAPTIVE_BINDING_COUNTERS) coherent buffer PlanCountersBlock { RbPlanCounters counters; };

// The sum of the weights adaptive_estimate.comp added for an image of `size` pixels.
float rbAdaptiveWeightTotal(uvec2 size) { return float(counters.weightSum) / float(rbAdaptiveWeightScale(size)); }

// One workgroup's claim of `request` rays: the rays claimed ahead of it. A workgroup that finds the budget spent
// claims nothing (and gets budgetRays: nothing is left), so the counter passes the budget by at most the claims of
// the workgroups in flight, and the host keeps the budget under 2^31 (kMaxAdaptiveRaysPerFrame): it cannot wrap,
// however far the rounded shares overshoot (a wrapped counter would hand rays out again).
uint rbAdaptiveClaim(uint request, uint budgetRays) {
  return counters.raysGranted >= budgetRays ? budgetRays : atomicAdd(counters.raysGranted, request);
}
#endif

#ifdef RB_ADAPTIVE_RAYS
// The plan in a ray generation shader: .x = the pixel's rays this frame, .y = the reprojected history mean, what
// a pixel given no ray writes (its estimate stays that of the frames before).
layout(set = 0, binding = RB_BINDING_RAY_PLAN) uniform sampler2D rayPlan;
#endif

#endif
