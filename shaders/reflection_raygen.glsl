#version 460
#extension GL_EXT_ray_tracing : require
#ifdef RB_REFLECTION_REORDER
#extension GL_NV_shader_invocation_reorder : require
#endif
#extension GL_GOOGLE_include_directive : require
// The reflection pass's ray generation, the body of the variants reflect.rgen and reflect_reorder.rgen (which
// defines RB_REFLECTION_REORDER), each also with RB_REFLECTION_CONVERGED_TILES (rows of shaders/variants.cmake):
// one source for the rays, only the trace call differs.
// Reflection rays from G-buffer surfaces under the roughness threshold: the mirror direction, or for glossy
// surfaces GGX directions sampled by visible normals (Heitz 2018), weighted by the Smith masking of the
// reflected direction. Everything rougher, and the sky, traces nothing.
// At half resolution (pc.halfResolution) the launch is one invocation per 2x2 block, each tracing for the pixel of
// its block that half_resolution.glsl picks this frame and writing the half-resolution image at its own index.
// With RB_REFLECTION_CONVERGED_TILES (full resolution only) the pixels of the tiles that rgb_converged.comp
// marked converged return at once: they already hold their outputs. The launch stays one invocation per pixel
// rather than covering a classifier's list of the tiles left, as the shadow and AO passes do: along the perf
// scene's fly-through, where every tile is traced, the list took the pass from 3.57 to 4.33 ms and this launch to
// 3.70 ms (NVIDIA H200, docs/performance.md), the same rays.

#include "raybridge_pass_constants.glsl"
layout(push_constant) uniform ReflectionPushConstants { ReflectionConstants pc; };
#include "half_resolution.glsl"
#include "pass_inputs.glsl"
#include "ray_counters.glsl"
#include "reflection_changes.glsl"
#include "reflection_common.glsl"
#ifdef RB_REFLECTION_CONVERGED_TILES
layout(set = 0, binding = RB_REFLECTION_BINDING_TILE_STATE, std430) readonly buffer TileState { uint tileState[]; };
#endif

layout(set = 0, binding = RB_BINDING_TLAS) uniform accelerationStructureEXT tlas;
layout(set = 0, binding = RB_BINDING_DEPTH) uniform sampler2D gDepth;
layout(set = 0, binding = RB_BINDING_NORMAL) uniform sampler2D gNormal;
layout(set = 0, binding = RB_BINDING_GEOMETRIC_NORMAL) uniform sampler2D gGeometricNormal;
layout(set = 0, binding = RB_REFLECTION_BINDING_ROUGHNESS_METALNESS) uniform sampler2D gRoughnessMetalness;
layout(set = 0, binding = RB_REFLECTION_BINDING_RADIANCE, rgba16f) uniform writeonly image2D outRadiance;

layout(location = 0) rayPayloadEXT ReflectionPayload payload;

#ifdef RB_REFLECTION_REORDER
// Coherence hint bits: NVIDIA advises few, as each one doubles the sort's keys; 8 bits tell 256 instances apart.
#define RB_REFLECTION_REORDER_HINT_BITS 8
#define RB_REFLECTION_REORDER_HINT_MASK 0xFFu
#endif

// GGX visible-normal sample in the tangent frame (z = normal); ve: view direction, alpha: roughness^2.
vec3 sampleGgxVndf(vec3 ve, float alpha, vec2 u) {
  vec3 vh = normalize(vec3(alpha * ve.x, alpha * ve.y, ve.z));
  float lensq = vh.x * vh.x + vh.y * vh.y;
  vec3 t1 = lensq > 0.0 ? vec3(-vh.y, vh.x, 0.0) * inversesqrt(lensq) : vec3(1.0, 0.0, 0.0);
  vec3 t2 = cross(vh, t1);
  float r = sqrt(u.x);
  float phi = 2.0 * RB_PI * u.y;
  float p1 = r * cos(phi);
  float p2 = r * sin(phi);
  float s = 0.5 * (1.0 + vh.z);
  p2 = (1.0 - s) * sqrt(1.0 - p1 * p1) + s * p2;
  vec3 nh = p1 * t1 + p2 * t2 + sqrt(max(0.0, 1.0 - p1 * p1 - p2 * p2)) * vh;
  return normalize(vec3(alpha * nh.x, alpha * nh.y, max(0.0, nh.z)));
}

float smithG1(float nDotX, float alpha) {
  float a2 = alpha * alpha;
  return 2.0 * nDotX / (nDotX + sqrt(a2 + (1.0 - a2) * nDotX * nDotX));
}

void main() {
  const bool halfRes = pc.halfResolution != 0u;
  uvec2 launch = gl_LaunchIDEXT.xy;
  if (any(greaterThanEqual(launch, halfRes ? rbHalfResSize(pc.gbuffer.size) : pc.gbuffer.size))) return;
#ifdef RB_REFLECTION_CONVERGED_TILES
  // The tile's index in the state buffer: as the converged-tile dispatches number their workgroups, row by row.
  const uint tilesPerRow = (pc.gbuffer.size.x + RB_SHADOW_TILE_SIZE - 1u) / RB_SHADOW_TILE_SIZE;
  const uvec2 tile = launch / RB_SHADOW_TILE_SIZE;
  if ((tileState[tile.x + tile.y * tilesPerRow] & RB_TILE_SKIP_CONVERGED) != 0u) return;
#endif
  uvec2 pixel = halfRes ? rbHalfResTracedPixel(launch, pc.gbuffer.frameIndex, pc.gbuffer.size) : launch;
  ivec2 ip = ivec2(pixel);
  ivec2 target = ivec2(launch);  // the output texel: the pixel, or at half resolution its sample
  float depth = texelFetch(gDepth, ip, 0).r;
  vec4 normalTexel = texelFetch(gNormal, ip, 0);
  float roughness = rbRoughness(normalTexel, gRoughnessMetalness, ip);
  if (rbIsSky(depth) || roughness > pc.roughnessThreshold) {
    imageStore(outRadiance, target, vec4(0.0));
    return;
  }
  vec3 n = rbDecodeNormal(normalTexel, rbNormalEncoding());
  vec3 ng = (pc.gbuffer.flags & RB_GB_GEOMETRIC_NORMAL) != 0u
                ? rbDecodeNormal(texelFetch(gGeometricNormal, ip, 0), rbNormalEncoding())
                : n;
  vec3 facing;
  vec3 origin = rbRayOrigin(pixel, depth, ng, facing);
  vec3 v = -normalize(rbCameraRelative(pixel, depth));
  if (dot(n, v) < 0.0) n = normalize(n + facing * (0.01 - dot(n, v)));  // a normal map tilted past the view
  float alpha = max(roughness * roughness, 1e-4);
  bool mirror = roughness < 0.02;
  uint count = mirror ? 1u : max(pc.raysPerPixel, 1u);  // every mirror ray would go the same way
  // A mirror shows a shadow's edge sharply: its hits trace (a soft or denoised screen value is not what it would see).
  const uint sunFromScreen = !mirror && roughness >= pc.sunCacheRoughness ? 1u : 0u;
  uint seed = rbPcg(pixel.x + pc.gbuffer.size.x * pixel.y + rbPcg(pc.gbuffer.frameIndex ^ 0x85ebca6bu));
  vec3 t, b;
  rbBasis(n, t, b);
  vec3 sum = vec3(0.0);
  uint traced = 0u;  // reflection rays, plus the shadow rays their hits traced
  bool stale = false;  // a ray met a change (ReflectionSettings::changedBoxes): the history is stale
  const vec3 toSun = dot(pc.sunDirection, pc.sunDirection) > 0.0 ? normalize(pc.sunDirection) : vec3(0.0);
  for (uint i = 0u; i < count; ++i) {
    vec3 dir;
    float weight = 1.0;
    if (mirror) {
      dir = reflect(-v, n);
    } else {
      vec2 u = vec2(rbToUnit(rbPcg(seed + 2u * i)), rbToUnit(rbPcg(seed + 2u * i + 1u)));
      vec3 ve = vec3(dot(v, t), dot(v, b), dot(v, n));
      vec3 h = sampleGgxVndf(ve, alpha, u);
      vec3 hw = h.x * t + h.y * b + h.z * n;
      dir = reflect(-v, hw);
      float nDotL = dot(n, dir);
      if (nDotL <= 0.0) continue;  // sampled below the surface: contributes nothing
      weight = smithG1(nDotL, alpha);
    }
    if (dot(dir, facing) <= 0.0) dir = normalize(dir - 2.0 * dot(dir, facing) * facing);
    payload.radiance = vec3(0.0);
    payload.shadowRays = 0u;
    payload.hitT = -1.0;
    payload.sunFromScreen = sunFromScreen;
    uint flags = (pc.gbuffer.flags & RB_GB_ALPHA_TEST) != 0u ? gl_RayFlagsNoneEXT : gl_RayFlagsOpaqueEXT;
#ifdef RB_REFLECTION_REORDER
    // The same ray, traced into a hit object (any-hit shaders run here); the threads are then regrouped so
    // that lanes shading the same instance (hence mostly the same material and textures) run the closest-hit
    // shader together, and misses together. The instance index is a hint only: its low bits suffice to group.
    hitObjectNV hitObject;
    hitObjectTraceRayNV(hitObject, tlas, flags, 0xFF, 0, 0, 0, origin, 0.0, dir, 1e30, 0);
    uint hint = hitObjectIsHitNV(hitObject) ? uint(hitObjectGetInstanceIdNV(hitObject)) : 0u;
    reorderThreadNV(hitObject, hint & RB_REFLECTION_REORDER_HINT_MASK, RB_REFLECTION_REORDER_HINT_BITS);
    hitObjectExecuteShaderNV(hitObject, 0);
#else
    traceRayEXT(tlas, flags, 0xFF, 0, 0, 0, origin, 0.0, dir, 1e30, 0);
#endif
    sum += weight * payload.radiance;
    traced += 1u + payload.shadowRays;
    if (pc.changedBoxCount != 0u && !stale) stale = rbReflectionChanged(origin, dir, payload.hitT, toSun);
  }
  // Samples below the surface contribute zero radiance but count: the estimator's denominator is `count`.
  imageStore(outRadiance, target, vec4(sum / float(count), stale ? 2.0 : 1.0));
  if (traced != 0u) rbCountRays(pixel, traced);
}
