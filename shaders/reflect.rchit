#version 460
#extension GL_EXT_ray_tracing : require
#extension GL_GOOGLE_include_directive : require
// Shades the surface a reflection ray hits (hit_shading.glsl): material, sun with a shadow ray, sky ambient,
// emission and the ManyLightPass's lights when given. The sun's visibility comes from the screen instead of a ray
// where the pass was given this frame's shadows and the hit is the surface on screen (rbSunFromScreen).
#include "raybridge_pass_constants.glsl"
layout(push_constant) uniform ReflectionPushConstants { ReflectionConstants pc; };
#include "pass_inputs.glsl"
#include "reflection_common.glsl"
#include "light_list.glsl"

layout(set = 0, binding = RB_BINDING_TLAS) uniform accelerationStructureEXT tlas;
layout(set = 0, binding = RB_BINDING_DEPTH) uniform sampler2D gDepth;
layout(set = 0, binding = RB_BINDING_GEOMETRIC_NORMAL) uniform sampler2D gGeometricNormal;
layout(set = 0, binding = RB_REFLECTION_BINDING_SUN_VISIBILITY) uniform sampler2D sunVisibility;
layout(set = 0, binding = RB_REFLECTION_BINDING_LIGHTS, std430) readonly buffer Lights { GpuLight lights[]; };
layout(location = 0) rayPayloadInEXT ReflectionPayload payload;
layout(location = 1) rayPayloadEXT float shadowHit;
hitAttributeEXT vec2 barycentrics;

// ReflectionFrame::sunVisibility at the pixel `hit` (TLAS space) projects to, where that pixel's G-buffer surface is
// the hit's own (reflection_pass.h, "Sun visibility from the screen"); false = trace. `ng`: the hit's geometric
// normal, facing the ray.
bool rbSunFromScreen(vec3 hit, vec3 ng, out float visibility) {
  visibility = 0.0;
  if (payload.sunFromScreen == 0u) return false;
  vec3 rel = hit - pc.gbuffer.cameraToTlas;
  // The side the ray arrived at must be the side the camera sees (a wall's back is not its front on screen).
  if (dot(ng, rel) >= 0.0) return false;
  // The inverses of what the G-buffer constants hold (no room for the forward matrices in the push constants); a
  // hit's few hundred flops against a shadow ray's traversal.
  vec4 clip = inverse(pc.gbuffer.inverseProjection) * vec4(inverse(pc.gbuffer.viewToWorld) * rel, 1.0);
  if (!(clip.w > 0.0)) return false;
  vec2 uv = clip.xy / clip.w * 0.5 + 0.5;
  if (!(all(greaterThanEqual(uv, vec2(0.0))) && all(lessThan(uv, vec2(1.0))))) return false;
  uvec2 pixel = min(uvec2(uv * vec2(pc.gbuffer.size)), pc.gbuffer.size - 1u);
  float depth = texelFetch(gDepth, ivec2(pixel), 0).r;
  if (rbIsSky(depth)) return false;
  vec3 p = rbCameraRelative(pixel, depth);
  vec3 n = rbDecodeNormal(texelFetch(gGeometricNormal, ivec2(pixel), 0), rbNormalEncoding());
  if (dot(n, p) > 0.0) n = -n;  // towards the camera, as ng is
  if (dot(n, ng) < RB_REFLECTION_SUN_CACHE_MIN_NORMAL_COS) return false;
  // Distance from the pixel's tangent plane, not along the view ray: a surface seen at a grazing angle spans a long
  // depth range within one pixel.
  if (abs(dot(rel - p, n)) > RB_REFLECTION_SUN_CACHE_DISTANCE_TOLERANCE * length(rel)) return false;
  visibility = clamp(texelFetch(sunVisibility, ivec2(pixel), 0).r, 0.0, 1.0);  // a filter's overshoot is no light
  return true;
}
#define RB_HIT_SUN_FROM_SCREEN

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
