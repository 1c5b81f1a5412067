#version 460
#extension GL_EXT_ray_tracing : require
#extension GL_GOOGLE_include_directive : require
// Shades the surface a primary ray hits, as reflection hits are shaded (hit_shading.glsl).
#include "primary_shading_common.glsl"
#include "light_list.glsl"
#include "shading_records.glsl"

layout(set = 0, binding = RB_BINDING_TLAS) uniform accelerationStructureEXT tlas;
layout(set = 0, binding = RB_PRIMARY_SHADING_BINDING_LIGHTS, std430) readonly buffer Lights { GpuLight lights[]; };
layout(location = 0) rayPayloadInEXT PrimaryShadingPayload payload;
layout(location = 1) rayPayloadEXT float shadowHit;
hitAttributeEXT vec2 barycentrics;

#include "hit_shading.glsl"

void main() {
  HitLighting l;
  l.sunDirection = pc.sunDirection;
  l.sunRadiance = pc.sunRadiance;
  l.skyRadiance = pc.skyRadiance;
  l.ambientIntensity = pc.ambientIntensity;
  l.lightCount = pc.lightCount;
  l.lightCandidates = pc.lightCandidates;
  l.alphaTest = (pc.camera.flags & RB_GB_ALPHA_TEST) != 0u;
  l.frameIndex = pc.camera.frameIndex;
  payload.radiance = rbShadeHit(l, barycentrics, payload.shadowRays);
  payload.hitT = gl_HitTEXT;
}
