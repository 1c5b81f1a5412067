// Shared by the PrimaryShadingPass's shaders: the push constants and the primary rays' payload.
#ifndef RAYBRIDGE_PRIMARY_SHADING_COMMON_GLSL
#define RAYBRIDGE_PRIMARY_SHADING_COMMON_GLSL

#include "raybridge_pass_constants.glsl"
layout(push_constant) uniform PrimaryShadingPushConstants { PrimaryShadingConstants pc; };

struct PrimaryShadingPayload {
  vec3 radiance;    // leaving the hit towards the eye; the sky on a miss
  uint shadowRays;  // traced from the hit (sun, local light), counted by the ray generation shader
  float hitT;       // distance from the eye along the (unit) ray direction; 0 = miss
};

#endif
