// Adaptive rays per pixel (sdk/src/adaptive_rays.h): the counters the two planning dispatches share, and the plan
// the ray generation shaders read.
#ifndef RAYBRIDGE_ADAPTIVE_RAYS_GLSL
#define RAYBRIDGE_ADAPTIVE_RAYS_GLSL

#include "raybridge_shader_interface.glsl"

// Filled with zeros before the first dispatch of each frame.
struct RbPlanCounters {
  uint weightSum;      // sum of the pixels' weights, in units of 1 / RB_ADAPTIVE_WEIGHT_SCALE
  uint surfacePixels;  // pixels that are not sky
  uint raysGranted;    // rays handed out so far by the allocation dispatch (never more than the budget)
  uint budget;         // the frame's ray budget, as the allocation dispatch resolved it
};

#ifdef RB_ADAPTIVE_RAYS
// The plan in a ray generation shader: .x = the pixel's rays this frame, .y = the reprojected history mean, what
// a pixel given no ray writes (its estimate stays that of the frames before).
layout(set = 0, binding = RB_BINDING_RAY_PLAN) uniform sampler2D rayPlan;
#endif

#endif
