#version 460
#extension GL_GOOGLE_include_directive : require
// Adaptive rays, step 2 of 2 at tile granularity (AdaptiveRayGranularity::Tile): each tile's rays per pixel this
// frame, the same for every surface pixel of the tile, so that the warp the ray generation shader runs the tile's
// launch cells in traces no lane longer than the others. As adaptive_allocate.comp, but per tile of pc.tileSize
// pixels (powers of two, at most 16, aligned to multiples of themselves): the budget R first gives every surface
// pixel pc.minRays; the rest is shared in proportion to the tile's summed weight, spread evenly over the tile's
// n surface pixels (expected total R: sum over tiles of n * extra * W_tile / (W n)), rounded stochastically with
// one random number per tile and capped at pc.maxRays. Each workgroup of 16x16 pixels claims its tiles' rays with
// one atomic; a tile whose rays do not all fit under R gets the most per pixel that does (floor(left / n)), so the
// budget holds and the tile stays uniform. Sky pixels get 0.
#define RB_ADAPTIVE_PLANNING
#include "adaptive_rays.glsl"
#include "raybridge_pass_constants.glsl"
#include "raybridge_sampling.glsl"

layout(local_size_x = 16, local_size_y = 16) in;
layout(push_constant) uniform AdaptivePushConstants { AdaptivePlanConstants pc; };
layout(set = 0, binding = RB_ADAPTIVE_BINDING_WEIGHTS, rg16f) uniform readonly image2D weightsIn;
layout(set = 0, binding = RB_ADAPTIVE_BINDING_PLAN, rg16f) uniform writeonly image2D planOut;

const uint kGroupSide = 16u;
const uint kGroupLanes = kGroupSide * kGroupSide;

shared float tileWeight[kGroupLanes];  // at a tile's first lane, after the reduction: the tile's summed weight
shared uint tileSurface[kGroupLanes];  // likewise: the tile's surface pixels
shared uint tileGranted[kGroupLanes];  // at a tile's first lane: the rays each of its surface pixels gets
shared uint scan[kGroupLanes];
shared uint groupBase;

void main() {
  const uvec2 pixel = gl_GlobalInvocationID.xy;
  const uvec2 local = gl_LocalInvocationID.xy;
  const uint lane = gl_LocalInvocationIndex;
  const uvec2 tile = pc.tileSize;
  const float surface = float(counters.surfacePixels);
  const float budget = pc.uniformRays > 0.0 ? min(pc.uniformRays * surface, float(pc.budget)) : float(pc.budget);
  const bool inside = all(lessThan(pixel, pc.size));
  const vec2 wv = inside ? imageLoad(weightsIn, ivec2(pixel)).xy : vec2(1.0, 0.0);
  const bool isSurface = wv.y > 0.0;  // sky weighs exactly 0
  tileWeight[lane] = wv.y;
  tileSurface[lane] = isSurface ? 1u : 0u;
  barrier();
  // Each tile's sums into its first lane: along the tile's rows, then down its first column. The loop bounds come
  // from push constants, uniform over the workgroup, as the barriers need.
  for (uint s = 1u; s < tile.x; s <<= 1u) {
    if ((local.x & (2u * s - 1u)) == 0u) {
      tileWeight[lane] += tileWeight[lane + s];
      tileSurface[lane] += tileSurface[lane + s];
    }
    barrier();
  }
  for (uint s = 1u; s < tile.y; s <<= 1u) {
    if ((local.x & (tile.x - 1u)) == 0u && (local.y & (2u * s - 1u)) == 0u) {
      tileWeight[lane] += tileWeight[lane + s * kGroupSide];
      tileSurface[lane] += tileSurface[lane + s * kGroupSide];
    }
    barrier();
  }
  const bool first = (local.x & (tile.x - 1u)) == 0u && (local.y & (tile.y - 1u)) == 0u;
  uint rays = 0u;  // per surface pixel of this lane's tile (first lanes only)
  uint n = 0u;
  if (first) n = tileSurface[lane];
  if (n > 0u) {
    const uvec2 tileId = pixel / tile;
    const uint tilesX = (pc.size.x + tile.x - 1u) / tile.x;
    float u = rbToUnit(rbPcg(tileId.x + tilesX * tileId.y + rbPcg(pc.frameIndex ^ 0x5bd1e995u)));
    float floorRays = float(min(pc.minRays, pc.maxRays));
    float share;
    if (budget >= floorRays * surface) {
      float total = rbAdaptiveWeightTotal(pc.size);
      float extra = budget - floorRays * surface;
      share = floorRays + (total > 0.0 ? extra * tileWeight[lane] / (total * float(n)) : 0.0);
    } else {
      share = budget / surface;  // not even the minimum everywhere: spread what there is evenly
    }
    rays = min(uint(floor(share + u)), pc.maxRays);
  }
  const uint request = rays * n;
  // Inclusive scan of the tiles' requests (Hillis-Steele over the workgroup; lanes other than a tile's first
  // request nothing).
  scan[lane] = request;
  barrier();
  for (uint offset = 1u; offset < kGroupLanes; offset <<= 1u) {
    uint add = lane >= offset ? scan[lane - offset] : 0u;
    barrier();
    scan[lane] += add;
    barrier();
  }
  // In integers, under the cap exactly (a float above 2^24 is rounded, above 2^32 out of range).
  const uint budgetRays = min(uint(min(budget, 4294967040.0)), pc.budget);
  if (lane == kGroupLanes - 1u) groupBase = rbAdaptiveClaim(scan[kGroupLanes - 1u], budgetRays);
  if (gl_WorkGroupID.xy == uvec2(0u) && lane == 0u) counters.budget = budgetRays;
  barrier();
  if (first) {
    const uint before = groupBase + scan[lane] - request;  // rays claimed ahead of this tile
    const uint left = before >= budgetRays ? 0u : budgetRays - before;
    tileGranted[lane] = request <= left ? rays : left / max(n, 1u);
  }
  barrier();
  const uint firstLane = (local.x & ~(tile.x - 1u)) + kGroupSide * (local.y & ~(tile.y - 1u));
  const uint granted = isSurface ? tileGranted[firstLane] : 0u;
  if (inside) imageStore(planOut, ivec2(pixel), vec4(float(granted), wv.x, 0.0, 0.0));
}
