#version 460
#extension GL_EXT_ray_tracing : require
#extension GL_GOOGLE_include_directive : require
// ManyLightPass, step 2 (the variants many_lights.rgen and many_lights_converged.rgen, with RB_ML_CONVERGED_TILES;
// rows of shaders/variants.cmake): the shadowed irradiance of every G-buffer pixel from the lights its tile lists
// (many_light_pass.h). Stochastic: each ray keeps one light in proportion to its unshadowed luminance among the
// candidates (all the tile's lights when it lists at most `candidates`, else `candidates` drawn uniformly from its
// list: resampled importance sampling) and traces one shadow ray to it:
//   estimate = f(y) / p(y) * s * sum_j p(x_j)     (p = luminance of the unshadowed irradiance; s = 1 when every
//                                                  listed light is a candidate, else n / M for M uniform draws
//                                                  from n listed lights)
// which is unbiased wherever p > 0 covers f > 0 (it does: p is f's luminance before the shadow ray).
// Exact, or a tile with no more lights than rays: one ray per light.
// With RB_ML_CONVERGED_TILES (ManyLightSettings::schedule.convergedTiles) the pixels of the 8x8 tiles that rgb_converged.comp
// marked converged return at once: they already hold their outputs.
#include "raybridge_pass_constants.glsl"
layout(push_constant) uniform ManyLightPushConstants { ManyLightConstants pc; };
#include "light_list.glsl"
#include "pass_inputs.glsl"
#include "ray_counters.glsl"

layout(set = 0, binding = RB_BINDING_TLAS) uniform accelerationStructureEXT tlas;
layout(set = 0, binding = RB_BINDING_DEPTH) uniform sampler2D gDepth;
layout(set = 0, binding = RB_BINDING_NORMAL) uniform sampler2D gNormal;
layout(set = 0, binding = RB_BINDING_GEOMETRIC_NORMAL) uniform sampler2D gGeometricNormal;
layout(set = 0, binding = RB_ML_BINDING_LIGHTS, std430) readonly buffer Lights { GpuLight lights[]; };
layout(set = 0, binding = RB_ML_BINDING_TILES, std430) readonly buffer Tiles { uint tiles[]; };
layout(set = 0, binding = RB_ML_BINDING_IRRADIANCE, rgba16f) uniform writeonly image2D outIrradiance;
#ifdef RB_ML_CONVERGED_TILES
layout(set = 0, binding = RB_ML_BINDING_TILE_STATE, std430) readonly buffer TileState { uint tileState[]; };
#endif

// -1 = occluded (set before tracing), 0 = reached the light (miss shader).
layout(location = 0) rayPayloadEXT float hitT;

uint gRayFlags;
vec3 gOrigin;
uint gRays = 0u;

// 1 when nothing blocks the way from the surface to the light (a point on its disk for a soft light).
float visibility(GpuLight light, vec3 toLight, float lightDistance, inout uint seed) {
  vec3 dir = toLight;
  float tMax = 1e30;
  if (light.softness > 0.0) {
    // One point of the disk facing the surface, uniform in area: radius sqrt(u), angle 2 pi v.
    seed = rbPcg(seed);
    float radius = sqrt(rbToUnit(seed));
    seed = rbPcg(seed);
    float angle = rbToUnit(seed) * 2.0 * RB_PI;
    vec2 d = radius * vec2(cos(angle), sin(angle));
    vec3 t, b;
    rbBasis(toLight, t, b);
    if (light.type == RB_LIGHT_DIRECTIONAL) {
      dir = normalize(toLight + light.softness * (d.x * t + d.y * b));
    } else {
      vec3 target = light.position + light.softness * (d.x * t + d.y * b);
      dir = target - gOrigin;
      tMax = length(dir);
      dir /= tMax;
      tMax *= 0.999;
    }
  } else if (light.type != RB_LIGHT_DIRECTIONAL) {
    tMax = 0.999 * length(light.position - gOrigin);
  }
  hitT = -1.0;
  traceRayEXT(tlas, gRayFlags, 0xFF, 0, 0, 0, gOrigin, 0.0, dir, tMax, 0);
  ++gRays;
  return hitT == 0.0 ? 1.0 : 0.0;
}

uint lightAt(uint tileBase, bool all, uint k) {
  if (all) return k;
  uint word = tiles[tileBase + 1u + (k >> 1)];
  return (k & 1u) != 0u ? word >> 16 : word & 0xFFFFu;
}

void main() {
  uvec2 pixel = gl_LaunchIDEXT.xy;
  if (any(greaterThanEqual(pixel, pc.gbuffer.size))) return;
#ifdef RB_ML_CONVERGED_TILES
  // The tile's index in the state buffer: as the converged-tile dispatches number their workgroups, row by row.
  const uvec2 convergedTile = pixel / RB_SHADOW_TILE_SIZE;
  const uint tilesPerRow = (pc.gbuffer.size.x + RB_SHADOW_TILE_SIZE - 1u) / RB_SHADOW_TILE_SIZE;
  if ((tileState[convergedTile.x + convergedTile.y * tilesPerRow] & RB_TILE_SKIP_CONVERGED) != 0u) return;
#endif
  ivec2 ip = ivec2(pixel);
  float depth = texelFetch(gDepth, ip, 0).r;
  vec3 irradiance = vec3(0.0);
  uvec2 tile = pixel / RB_ML_TILE_SIZE;
  uint tileBase = (tile.y * pc.tiles.x + tile.x) * RB_ML_TILE_UINTS;
  uint listed = tiles[tileBase];
  bool all = listed == RB_ML_TILE_OVERFLOW;
  uint n = all ? pc.lightCount : listed;
  if (!rbIsSky(depth) && n > 0u) {
    vec3 normal = rbDecodeNormal(texelFetch(gNormal, ip, 0), rbNormalEncoding());
    vec3 ng = (pc.gbuffer.flags & RB_GB_GEOMETRIC_NORMAL) != 0u
                  ? rbDecodeNormal(texelFetch(gGeometricNormal, ip, 0), rbNormalEncoding())
                  : normal;
    vec3 facing;
    gOrigin = rbRayOrigin(pixel, depth, ng, facing);
    vec3 surface = rbSurfacePoint(pixel, depth);
    gRayFlags = ((pc.gbuffer.flags & RB_GB_ALPHA_TEST) != 0u ? gl_RayFlagsNoneEXT : gl_RayFlagsOpaqueEXT) |
                gl_RayFlagsTerminateOnFirstHitEXT | gl_RayFlagsSkipClosestHitShaderEXT;
    uint seed = rbPcg(pixel.x + pc.gbuffer.size.x * pixel.y + rbPcg(pc.gbuffer.frameIndex ^ 0x68bc21ebu));
    uint rays = max(pc.raysPerPixel, 1u);
    if (pc.mode == RB_ML_EXACT || n <= rays) {
      for (uint k = 0u; k < n; ++k) {
        GpuLight light = lights[lightAt(tileBase, all, k)];
        vec3 toLight;
        float distance;
        vec3 e = rbLightIrradiance(light, surface, normal, facing, toLight, distance);
        if (rbLuminance(e) > 0.0) irradiance += e * visibility(light, toLight, distance, seed);
      }
    } else {
      // The candidates: every light of the tile when it lists at most `candidates` (the selection is then exactly
      // proportional to the unshadowed contribution), else `candidates` drawn uniformly from its list. One pass
      // over them feeds up to four reservoirs at once, one per ray, so the lights are weighed once per pixel and
      // not once per ray (the rays share the candidates; each is still an unbiased estimate).
      uint m = max(pc.candidates, 1u);
      bool enumerate = n <= m;
      uint count = enumerate ? n : m;
      float scale = enumerate ? 1.0 : float(n) / float(m);  // RIS: the mean weight times the listed lights
      uint candidateSeed = rbPcg(seed ^ 0x9e3779b9u);
      for (uint first = 0u; first < rays; first += 4u) {
        uint batch = min(4u, rays - first);
        float weightSum = 0.0;
        // Only the kept light and its weight per reservoir: its irradiance and direction are evaluated again
        // before its ray, so that little state is live across traceRayEXT (the ray tracing hardware keeps the
        // live registers of the ray generation shader during each trace; more of them means fewer rays in flight).
        uint kept[4] = uint[4](0u, 0u, 0u, 0u);
        float keptWeight[4] = float[4](0.0, 0.0, 0.0, 0.0);
        uint draw = candidateSeed;  // the same candidates for every batch
        for (uint c = 0u; c < count; ++c) {
          uint k = c;
          if (!enumerate) {
            draw = rbPcg(draw);
            k = min(uint(rbToUnit(draw) * float(n)), n - 1u);
          }
          uint index = lightAt(tileBase, all, k);
          vec3 toLight;
          float distance;
          vec3 e = rbLightIrradiance(lights[index], surface, normal, facing, toLight, distance);
          float w = rbLuminance(e);
          if (w <= 0.0) continue;
          weightSum += w;
          for (uint b = 0u; b < batch; ++b) {
            seed = rbPcg(seed);
            if (rbToUnit(seed) * weightSum < w) kept[b] = index, keptWeight[b] = w;
          }
        }
        if (weightSum <= 0.0) break;  // no candidate can light the point: no ray, in any batch
        for (uint b = 0u; b < batch; ++b) {
          GpuLight light = lights[kept[b]];
          vec3 toLight;
          float distance;
          vec3 e = rbLightIrradiance(light, surface, normal, facing, toLight, distance);
          float v = visibility(light, toLight, distance, seed);
          irradiance += e * (v * weightSum * scale / keptWeight[b]);
        }
      }
      irradiance /= float(rays);
    }
  }
  imageStore(outIrradiance, ip, vec4(irradiance, 1.0));
  if (gRays != 0u) rbCountRays(pixel, gRays);
}
