#version 460
#extension GL_EXT_ray_tracing : require
#extension GL_GOOGLE_include_directive : require
// Shades the surface a reflection ray hits: its material (factors and textures), the sun with a shadow ray
// (Lambert diffuse for dielectrics, the base colour as specular colour for metals), the sky's ambient light,
// and emission. Attributes come from the instance's shading record, fetched by device address.
#include "raybridge_pass_constants.glsl"
layout(push_constant) uniform ReflectionPushConstants { ReflectionConstants pc; };
#include "pass_inputs.glsl"
#include "ray_counters.glsl"
#include "reflection_common.glsl"

layout(set = 0, binding = RB_BINDING_TLAS) uniform accelerationStructureEXT tlas;
layout(location = 0) rayPayloadInEXT ReflectionPayload payload;
layout(location = 1) rayPayloadEXT float shadowHit;
hitAttributeEXT vec2 barycentrics;

void main() {
  ShadingRecord r = records[gl_InstanceID];
  vec3 bary = vec3(1.0 - barycentrics.x - barycentrics.y, barycentrics.x, barycentrics.y);
  uint i0 = rbLoadIndex(r, 3u * uint(gl_PrimitiveID));
  uint i1 = rbLoadIndex(r, 3u * uint(gl_PrimitiveID) + 1u);
  uint i2 = rbLoadIndex(r, 3u * uint(gl_PrimitiveID) + 2u);
  vec3 dir = gl_WorldRayDirectionEXT;
  // Object-to-world for normals: the inverse transpose, i.e. the world-to-object matrix applied on the right.
  mat3 normalToWorld = transpose(mat3(gl_WorldToObjectEXT));
  vec3 ng;
  if (r.positionFormat == 106u) {
    vec3 p0 = rbLoadVec3(r.positions, i0 * r.positionStride);
    vec3 p1 = rbLoadVec3(r.positions, i1 * r.positionStride);
    vec3 p2 = rbLoadVec3(r.positions, i2 * r.positionStride);
    ng = normalize(normalToWorld * cross(p1 - p0, p2 - p0));
  } else {
    ng = -dir;  // positions in a packed format: face the ray
  }
  if (dot(ng, dir) > 0.0) ng = -ng;
  vec3 n = ng;
  if (!rbIsNull(r.normals)) {
    vec3 sn = bary.x * rbLoadVec3(r.normals, i0 * r.normalStride) + bary.y * rbLoadVec3(r.normals, i1 * r.normalStride) +
              bary.z * rbLoadVec3(r.normals, i2 * r.normalStride);
    sn = normalize(normalToWorld * sn);
    n = dot(sn, ng) < 0.0 ? -sn : sn;
  }
  vec2 uv = rbHitTexcoord(r, uint(gl_PrimitiveID), barycentrics);
  GpuMaterial m = materials[r.material];
  vec4 base = m.baseColor;
  if (m.baseColorTexture != 0xFFFFFFFFu) {
    base *= textureLod(textures[nonuniformEXT(m.baseColorTexture)], rbMaterialUv(m, uv), 0.0);
  }
  float metallic = m.metallic;
  if (m.metallicRoughnessTexture != 0xFFFFFFFFu) {
    metallic *= textureLod(textures[nonuniformEXT(m.metallicRoughnessTexture)], uv, 0.0).b;
  }
  vec3 hit = gl_WorldRayOriginEXT + gl_HitTEXT * dir;
  vec3 toSun = normalize(pc.sunDirection);
  float nDotL = dot(n, toSun);
  float sunVisible = 0.0;
  if (nDotL > 0.0 && dot(ng, toSun) > 0.0) {
    vec3 origin = rbOffsetRayOrigin(hit + ng * 1e-4 * max(1.0, gl_HitTEXT), ng);
    shadowHit = -1.0;
    uint flags = gl_RayFlagsTerminateOnFirstHitEXT | gl_RayFlagsSkipClosestHitShaderEXT;
    if ((pc.gbuffer.flags & RB_GB_ALPHA_TEST) == 0u) flags |= gl_RayFlagsOpaqueEXT;
    traceRayEXT(tlas, flags, 0xFF, 0, 0, 1, origin, 0.0, toSun, 1e30, 1);
    sunVisible = shadowHit == 0.0 ? 1.0 : 0.0;
    // Shadow rays from hits are the pass's rays too.
    rbCountRays(gl_LaunchIDEXT.xy, 1u);
  }
  vec3 diffuse = base.rgb * (1.0 - metallic) / RB_PI;
  vec3 specularColour = mix(vec3(0.04), base.rgb, metallic);
  // Direct sun: diffuse, plus a broad specular approximation so metals are not black under the sun.
  vec3 direct = (diffuse + specularColour / RB_PI) * pc.sunRadiance * max(nDotL, 0.0) * sunVisible;
  vec3 ambient = (base.rgb * (1.0 - metallic) + specularColour * metallic) * pc.skyRadiance * pc.ambientIntensity;
  vec3 emissive = m.emissive;
  if (m.emissiveTexture != 0xFFFFFFFFu) emissive *= textureLod(textures[nonuniformEXT(m.emissiveTexture)], uv, 0.0).rgb;
  payload.radiance = direct + ambient + emissive;
}
