#version 460
#extension GL_GOOGLE_include_directive : require
#extension GL_KHR_shader_subgroup_ballot : require
// ManyLightPass, step 1: per 16x16-pixel tile (one workgroup), the bounding box of the tile's surface points and
// the lights whose range and cone can reach it, in light order (per chunk of 64 lights a prefix count from subgroup
// ballots, so the list is the same on every run and a chunk costs two barriers). More than RB_ML_MAX_TILE_LIGHTS: the tile is marked to sample all lights. Sky-only
// tiles list none.
#include "raybridge_pass_constants.glsl"
layout(push_constant) uniform ManyLightPushConstants { ManyLightConstants pc; };
#include "light_list.glsl"
#include "pass_inputs.glsl"

layout(local_size_x = 8, local_size_y = 8) in;
layout(set = 0, binding = RB_ML_CULL_BINDING_DEPTH) uniform sampler2D gDepth;
layout(set = 0, binding = RB_ML_CULL_BINDING_LIGHTS, std430) readonly buffer Lights { GpuLight lights[]; };
layout(set = 0, binding = RB_ML_CULL_BINDING_TILES, std430) writeonly buffer Tiles { uint tiles[]; };

shared vec3 boxMin[64];
shared vec3 boxMax[64];
shared uint subgroupCounts[64];  // lights reaching the tile per subgroup of the current chunk
shared uint packedList[RB_ML_MAX_TILE_LIGHTS / 2];

// Whether light `index` can reach some point of the box [lo, hi]. The range test reads the light's first 16 bytes
// only (directional lights have range 0): most lights of a large list are out of range of a tile, and every tile
// tests every light, so the rest of the 64-byte record is read for the few that pass.
bool reaches(uint index, vec3 lo, vec3 hi) {
  vec3 position = lights[index].position;
  float range = lights[index].range;
  if (range > 0.0) {
    vec3 d = clamp(position, lo, hi) - position;
    if (dot(d, d) > range * range) return false;
  }
  if (lights[index].type != RB_LIGHT_SPOT) return true;
  // The cone against the box's bounding sphere: outside when the angle to its centre exceeds the cone's
  // half-angle by more than the sphere's angular radius.
  vec3 c = 0.5 * (lo + hi) - position;
  float r = 0.5 * length(hi - lo), dist = length(c);
  if (dist > r) {
    float angle = acos(clamp(dot(c / dist, lights[index].direction), -1.0, 1.0));
    if (angle - asin(min(r / dist, 1.0)) > acos(clamp(lights[index].cosOuter, -1.0, 1.0))) return false;
  }
  return true;
}

void main() {
  uint tid = gl_LocalInvocationIndex;
  uvec2 tile = gl_WorkGroupID.xy;
  if (any(greaterThanEqual(tile, pc.tiles))) return;  // whole workgroups only: barriers stay uniform
  vec3 lo = vec3(1e30), hi = vec3(-1e30);
  uvec2 base = tile * RB_ML_TILE_SIZE + gl_LocalInvocationID.xy * 2u;
  for (uint k = 0u; k < 4u; ++k) {
    uvec2 pixel = base + uvec2(k & 1u, k >> 1);
    if (any(greaterThanEqual(pixel, pc.gbuffer.size))) continue;
    float depth = texelFetch(gDepth, ivec2(pixel), 0).r;
    if (rbIsSky(depth)) continue;
    vec3 p = rbSurfacePoint(pixel, depth);
    lo = min(lo, p);
    hi = max(hi, p);
  }
  boxMin[tid] = lo;
  boxMax[tid] = hi;
  for (uint i = tid; i < RB_ML_MAX_TILE_LIGHTS / 2; i += 64u) packedList[i] = 0u;
  barrier();
  for (uint s = 32u; s > 0u; s >>= 1) {
    if (tid < s) {
      boxMin[tid] = min(boxMin[tid], boxMin[tid + s]);
      boxMax[tid] = max(boxMax[tid], boxMax[tid + s]);
    }
    barrier();
  }
  lo = boxMin[0];
  hi = boxMax[0];
  // A margin for the reconstruction error of the points (they are offset before tracing).
  vec3 margin = vec3(1e-3) * max(1.0, max(length(lo), length(hi)) * 1e-3);
  lo -= margin;
  hi += margin;
  bool empty = lo.x > hi.x;
  uint total = 0u;
  bool overflow = false;
  // Lights go to invocations by subgroup, then lane, so that the count before an invocation is the counts of the
  // lower subgroups plus its exclusive ballot count: light order, whatever the subgroup size.
  uint lane = gl_SubgroupID * gl_SubgroupSize + gl_SubgroupInvocationID;
  for (uint chunk = 0u; chunk < pc.lightCount && !empty; chunk += 64u) {
    uint index = chunk + lane;
    bool flag = index < pc.lightCount && reaches(index, lo, hi);
    uvec4 ballot = subgroupBallot(flag);
    if (subgroupElect()) subgroupCounts[gl_SubgroupID] = subgroupBallotBitCount(ballot);
    barrier();
    uint before = 0u, chunkTotal = 0u;
    for (uint g = 0u; g < gl_NumSubgroups; ++g) {
      if (g < gl_SubgroupID) before += subgroupCounts[g];
      chunkTotal += subgroupCounts[g];
    }
    uint slot = total + before + subgroupBallotExclusiveBitCount(ballot);
    if (flag && slot < RB_ML_MAX_TILE_LIGHTS)
      atomicOr(packedList[slot >> 1], (index & 0xFFFFu) << ((slot & 1u) * 16u));
    total += chunkTotal;
    barrier();
    if (total > RB_ML_MAX_TILE_LIGHTS) {
      overflow = true;
      break;
    }
  }
  uint tileBase = (tile.y * pc.tiles.x + tile.x) * RB_ML_TILE_UINTS;
  if (tid == 0u) tiles[tileBase] = overflow ? RB_ML_TILE_OVERFLOW : (empty ? 0u : total);
  for (uint i = tid; i < RB_ML_MAX_TILE_LIGHTS / 2; i += 64u) tiles[tileBase + 1u + i] = packedList[i];
}
