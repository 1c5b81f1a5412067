#version 460
#extension GL_EXT_ray_tracing : require
#extension GL_GOOGLE_include_directive : require
// Shades the surface a reflection ray hits (hit_shading.glsl): material, sun with a shadow ray, sky ambient,
// emission and the ManyLightPass's lights when given.
#include "raybridge_pass_constants.glsl"
layout(push_constant) uniform ReflectionPushConstants { ReflectionConstants pc; };
#include "pass_inputs.glsl"
#include "reflection_common.glsl"
#include "light_list.glsl"

layout(set = 0, binding = RB_BINDING_TLAS) uniform accelerationStructureEXT tlas;
layout(set = 0, binding = RB_REFLECTION_BINDING_LIGHTS, std430) readonly buffer Lights { GpuLight lights[]; };
layout(location = 0) rayPayloadInEXT ReflectionPayload payload;
layout(location = 1) rayPayloadEXT float shadowHit;
hitAttributeEXT vec2 barycentrics;

#include "hit_shading.glsl"

void main() {
  HitLighting l;
  l.sunDirection = normalize(pc.sunDirection);
  l.sunRadiance = pc.sunRadiance;
  l.skyRadiance = pc.skyRadiance;
  l.ambientIntensity = pc.ambientIntensity;
  l.lightCount = pc.lightCount;
  l.lightCandidates = pc.lightCandidates;
  l.alphaTest = (pc.gbuffer.flags & RB_GB_ALPHA_TEST) != 0u;
  l.frameIndex = pc.gbuffer.frameIndex;
  // The pass's rays too: the ray generation shader counts them with its own.
  payload.radiance = rbShadeHit(l, barycentrics, payload.shadowRays);
  payload.hitT = gl_HitTEXT;
}
