#version 460
#extension GL_GOOGLE_include_directive : require
// The shadow pass's tile classifier, one workgroup per 8x8-pixel tile: runs the ray generation shader's own
// per-pixel test (rbShadowPixel) on every pixel. A tile where no pixel needs a ray gets its outputs here, the values
// the ray generation shader would have written; any other tile is appended to the tile list, whose trace arguments
// grow by one tile. With pc.convergedTiles, a tile that needs rays but that shadow_converged.comp marked converged
// is skipped too (its outputs are already written). Counts the tiles traced and skipped, the converged ones and the
// rays they saved, for PassStats. The body of the variants shadow_classify.comp and shadow_classify_distance.comp
// (RB_WRITE_HIT_DISTANCE: the occluder-distance output too), rows of shaders/variants.cmake.
#include "raybridge_pass_constants.glsl"
layout(push_constant) uniform ShadowPushConstants { ShadowConstants pc; };
#include "ray_counters.glsl"
#include "shadow_pixel.glsl"
#include "shadow_tiles.glsl"

layout(local_size_x = RB_SHADOW_TILE_SIZE, local_size_y = RB_SHADOW_TILE_SIZE) in;
layout(set = 0, binding = RB_SHADOW_BINDING_VISIBILITY, r16f) uniform writeonly image2D outVisibility;
#ifdef RB_WRITE_HIT_DISTANCE
layout(set = 0, binding = RB_SHADOW_BINDING_HIT_DISTANCE, r32f) uniform writeonly image2D outHitDistance;
#endif
layout(set = 0, binding = RB_SHADOW_BINDING_TILE_STATE, std430) buffer TileState { uint tileState[]; };

shared uint tracedPixels;

void main() {
  if (gl_LocalInvocationIndex == 0u) tracedPixels = 0u;
  barrier();
  uvec2 pixel = gl_GlobalInvocationID.xy;
  bool inside = all(lessThan(pixel, pc.gbuffer.size));
  uint kind = inside ? rbShadowPixel(pixel).kind : RB_SHADOW_PIXEL_SKY;
  if (kind == RB_SHADOW_PIXEL_TRACE) atomicAdd(tracedPixels, 1u);
  barrier();
  if (tracedPixels == 0u) {
    if (inside) {
      imageStore(outVisibility, ivec2(pixel), vec4(rbShadowUntracedVisibility(kind)));
#ifdef RB_WRITE_HIT_DISTANCE
      imageStore(outHitDistance, ivec2(pixel), vec4(0.0));
#endif
    }
    if (gl_LocalInvocationIndex == 0u) atomicAdd(tilesSkipped, 1u);
  } else if (pc.convergedTiles != 0u &&
             (tileState[gl_WorkGroupID.x + gl_WorkGroupID.y * gl_NumWorkGroups.x] & RB_TILE_SKIP_CONVERGED) != 0u) {
    if (gl_LocalInvocationIndex == 0u) {
      atomicAdd(tilesSkipped, 1u);
      atomicAdd(tilesConverged, 1u);
      atomicAdd(raysSaved, tracedPixels * max(pc.raysPerPixel, 1u));
    }
  } else if (gl_LocalInvocationIndex == 0u) {
    uint slot = atomicAdd(traceArgs[0], RB_SHADOW_TILE_SIZE) / RB_SHADOW_TILE_SIZE;
    tiles[slot] = gl_WorkGroupID.x | (gl_WorkGroupID.y << 16);
    atomicAdd(tilesTraced, 1u);
  }
}
