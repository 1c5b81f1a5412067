#version 460
#extension GL_EXT_ray_tracing : require
#extension GL_GOOGLE_include_directive : require
// Shades the surface a reflection ray hits: its material (factors and textures), the sun with a shadow ray
// (Lambert diffuse for dielectrics, the base colour as specular colour for metals), the sky's ambient light,
// and emission, and the local lights of a ManyLightPass when given: one light per hit, chosen among
// pc.lightCandidates drawn uniformly from the list in proportion to its unshadowed luminance there (resampled
// importance sampling, unbiased), with its shadow ray. Attributes come from the instance's shading record,
// fetched by device address.
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
  vec3 origin = rbOffsetRayOrigin(hit + ng * 1e-4 * max(1.0, gl_HitTEXT), ng);
  uint flags = gl_RayFlagsTerminateOnFirstHitEXT | gl_RayFlagsSkipClosestHitShaderEXT;
  if ((pc.gbuffer.flags & RB_GB_ALPHA_TEST) == 0u) flags |= gl_RayFlagsOpaqueEXT;
  if (nDotL > 0.0 && dot(ng, toSun) > 0.0 && any(greaterThan(pc.sunRadiance, vec3(0.0)))) {
    shadowHit = -1.0;
    traceRayEXT(tlas, flags, 0xFF, 0, 0, 1, origin, 0.0, toSun, 1e30, 1);
    sunVisible = shadowHit == 0.0 ? 1.0 : 0.0;
    ++payload.shadowRays;  // the pass's rays too: counted by the ray generation shader
  }
  // Local lights: irradiance E from one resampled light (see the top), shadowed.
  vec3 localIrradiance = vec3(0.0);
  uint count = pc.lightCount;
  if (count > 0u) {
    uvec3 bits = floatBitsToUint(dir);
    uint seed = rbPcg(gl_LaunchIDEXT.x + 65521u * gl_LaunchIDEXT.y + rbPcg(pc.gbuffer.frameIndex ^ 0x2545f491u));
    seed = rbPcg(seed ^ rbPcg(bits.x ^ rbPcg(bits.y ^ bits.z)));
    uint m = max(pc.lightCandidates, 1u);
    float weightSum = 0.0, keptWeight = 0.0, keptDistance = 0.0;
    vec3 keptE = vec3(0.0), keptDir = vec3(0.0);
    for (uint c = 0u; c < m; ++c) {
      seed = rbPcg(seed);
      uint index = min(uint(rbToUnit(seed) * float(count)), count - 1u);
      vec3 toLight;
      float distance;
      vec3 e = rbLightIrradiance(lights[index], hit, n, ng, toLight, distance);
      float w = rbLuminance(e);
      if (w <= 0.0) continue;
      weightSum += w;
      seed = rbPcg(seed);
      if (rbToUnit(seed) * weightSum < w) keptWeight = w, keptE = e, keptDir = toLight, keptDistance = distance;
    }
    if (weightSum > 0.0) {
      shadowHit = -1.0;
      float tMax = keptDistance >= 1e29 ? 1e30 : 0.999 * keptDistance;
      traceRayEXT(tlas, flags, 0xFF, 0, 0, 1, origin, 0.0, keptDir, tMax, 1);
      ++payload.shadowRays;
      if (shadowHit == 0.0) localIrradiance = keptE * (weightSum * float(count) / (float(m) * keptWeight));
    }
  }
  vec3 diffuse = base.rgb * (1.0 - metallic) / RB_PI;
  vec3 specularColour = mix(vec3(0.04), base.rgb, metallic);
  // Direct light: diffuse, plus a broad specular approximation so metals are not black under the sun.
  vec3 direct = (diffuse + specularColour / RB_PI) * (pc.sunRadiance * max(nDotL, 0.0) * sunVisible + localIrradiance);
  vec3 ambient = (base.rgb * (1.0 - metallic) + specularColour * metallic) * pc.skyRadiance * pc.ambientIntensity;
  vec3 emissive = m.emissive;
  if (m.emissiveTexture != 0xFFFFFFFFu) emissive *= textureLod(textures[nonuniformEXT(m.emissiveTexture)], uv, 0.0).rgb;
  payload.radiance = direct + ambient + emissive;
}
