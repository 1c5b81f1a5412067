// Shades the surface a ray hit, in a closest-hit shader (reflection hits, the PrimaryShadingPass): its material
// (factors and textures), the sun with a shadow ray (Lambert diffuse for dielectrics, the base colour as specular
// colour for metals), the sky's ambient light, and emission, and the local lights of a ManyLightPass when given:
// one light per hit, chosen among `lightCandidates` drawn uniformly from the list in proportion to its unshadowed
// luminance there (resampled importance sampling, unbiased), with its shadow ray. Attributes come from the
// instance's shading record, fetched by device address.
//
// The including shader declares first: `tlas` (accelerationStructureEXT), `lights` (GpuLight[], light_list.glsl)
// and the shadow rays' payload `shadowHit` (float, location 1; occlusion.rmiss is miss shader 1). With
// RB_HIT_SUN_FROM_SCREEN defined it also declares `bool rbSunFromScreen(vec3 hit, vec3 ng, out float visibility)`
// (ng: the hit's geometric normal, facing the ray): true = the sun's visibility of the hit is known without a ray.
#ifndef RAYBRIDGE_HIT_SHADING_GLSL
#define RAYBRIDGE_HIT_SHADING_GLSL

#include "light_list.glsl"
#include "raybridge_sampling.glsl"
#include "shading_records.glsl"

// What lights a hit; each pass fills it from its own push constants.
struct HitLighting {
  vec3 sunDirection;  // towards the sun, unit length
  vec3 sunRadiance;   // 0 = no sun (no shadow ray)
  vec3 skyRadiance;
  float ambientIntensity;  // sky light on the surface: ambientIntensity * skyRadiance
  uint lightCount;         // entries of `lights`; 0 = no local light
  uint lightCandidates;
  bool alphaTest;   // shadow rays run the any-hit shaders of non-opaque geometry (RB_GB_ALPHA_TEST)
  uint frameIndex;  // the noise seed
};

// The radiance leaving the hit of the current closest-hit invocation towards the ray's origin. Adds the shadow
// rays it traced to `shadowRays`.
vec3 rbShadeHit(HitLighting l, vec2 barycentrics, inout uint shadowRays) {
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
  GpuMaterial m = materials[min(r.material, uint(materials.length()) - 1u)];
  vec4 base = m.baseColor;
  if (m.baseColorTexture != 0xFFFFFFFFu) {
    base *= textureLod(textures[nonuniformEXT(m.baseColorTexture)], rbMaterialUv(m, uv), 0.0);
  }
  float metallic = m.metallic;
  if (m.metallicRoughnessTexture != 0xFFFFFFFFu) {
    metallic *= textureLod(textures[nonuniformEXT(m.metallicRoughnessTexture)], uv, 0.0).b;
  }
  vec3 hit = gl_WorldRayOriginEXT + gl_HitTEXT * dir;
  vec3 toSun = l.sunDirection;
  float nDotL = dot(n, toSun);
  float sunVisible = 0.0;
  vec3 origin = rbOffsetRayOrigin(hit + ng * 1e-4 * max(1.0, gl_HitTEXT), ng);
  uint flags = gl_RayFlagsTerminateOnFirstHitEXT | gl_RayFlagsSkipClosestHitShaderEXT;
  if (!l.alphaTest) flags |= gl_RayFlagsOpaqueEXT;
  if (nDotL > 0.0 && dot(ng, toSun) > 0.0 && any(greaterThan(l.sunRadiance, vec3(0.0)))) {
#ifdef RB_HIT_SUN_FROM_SCREEN
    // Where this frame's shadows already hold the hit's sun visibility (the including shader decides), no ray.
    if (!rbSunFromScreen(hit, ng, sunVisible))
#endif
    {
      shadowHit = -1.0;
      traceRayEXT(tlas, flags, 0xFF, 0, 0, 1, origin, 0.0, toSun, 1e30, 1);
      sunVisible = shadowHit == 0.0 ? 1.0 : 0.0;
      ++shadowRays;
    }
  }
  // Local lights: irradiance E from one resampled light (see the top), shadowed.
  vec3 localIrradiance = vec3(0.0);
  uint count = l.lightCount;
  if (count > 0u) {
    uvec3 bits = floatBitsToUint(dir);
    uint seed = rbPcg(gl_LaunchIDEXT.x + 65521u * gl_LaunchIDEXT.y + rbPcg(l.frameIndex ^ 0x2545f491u));
    seed = rbPcg(seed ^ rbPcg(bits.x ^ rbPcg(bits.y ^ bits.z)));
    uint candidates = max(l.lightCandidates, 1u);
    float weightSum = 0.0, keptWeight = 0.0, keptDistance = 0.0;
    vec3 keptE = vec3(0.0), keptDir = vec3(0.0);
    for (uint c = 0u; c < candidates; ++c) {
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
      ++shadowRays;
      if (shadowHit == 0.0) localIrradiance = keptE * (weightSum * float(count) / (float(candidates) * keptWeight));
    }
  }
  vec3 diffuse = base.rgb * (1.0 - metallic) / RB_PI;
  vec3 specularColour = mix(vec3(0.04), base.rgb, metallic);
  // Direct light: diffuse, plus a broad specular approximation so metals are not black under the sun.
  vec3 direct = (diffuse + specularColour / RB_PI) * (l.sunRadiance * max(nDotL, 0.0) * sunVisible + localIrradiance);
  vec3 ambient = (base.rgb * (1.0 - metallic) + specularColour * metallic) * l.skyRadiance * l.ambientIntensity;
  vec3 emissive = m.emissive;
  if (m.emissiveTexture != 0xFFFFFFFFu) emissive *= textureLod(textures[nonuniformEXT(m.emissiveTexture)], uv, 0.0).rgb;
  return direct + ambient + emissive;
}

#endif
