#version 460
#extension GL_GOOGLE_include_directive : require
// The AO pass's tile classifier (AoSettings::schedule.convergedTiles), one workgroup per 8x8-pixel tile, after
// shadow_converged.comp marked the converged tiles: a tile of sky alone gets its outputs here (1, as the ray
// generation shader writes for sky); a tile that shadow_converged.comp marked converged is skipped (its outputs, the
// kept-history marks, are already written); any other tile is appended to the tile list, whose trace arguments grow
// by one tile. Counts the tiles traced and skipped, the converged ones and the rays they saved, for PassStats.
#include "raybridge_pass_constants.glsl"
layout(push_constant) uniform AoPushConstants { AoConstants pc; };
#include "pass_inputs.glsl"
#include "ray_counters.glsl"
#include "shadow_tiles.glsl"

layout(local_size_x = RB_SHADOW_TILE_SIZE, local_size_y = RB_SHADOW_TILE_SIZE) in;
layout(set = 0, binding = RB_BINDING_DEPTH) uniform sampler2D gDepth;
layout(set = 0, binding = RB_AO_BINDING_OUTPUT, r16f) uniform writeonly image2D outAo;
layout(set = 0, binding = RB_AO_BINDING_TILE_STATE, std430) buffer TileState { uint tileState[]; };

shared uint surfacePixels;

void main() {
  if (gl_LocalInvocationIndex == 0u) surfacePixels = 0u;
  barrier();
  uvec2 pixel = gl_GlobalInvocationID.xy;
  bool inside = all(lessThan(pixel, pc.gbuffer.size));
  bool surface = inside && !rbIsSky(texelFetch(gDepth, ivec2(pixel), 0).r);
  if (surface) atomicAdd(surfacePixels, 1u);
  barrier();
  if (surfacePixels == 0u) {
    if (inside) imageStore(outAo, ivec2(pixel), vec4(1.0));
    if (gl_LocalInvocationIndex == 0u) atomicAdd(tilesSkipped, 1u);
  } else if ((tileState[gl_WorkGroupID.x + gl_WorkGroupID.y * gl_NumWorkGroups.x] & RB_TILE_SKIP_CONVERGED) != 0u) {
    if (gl_LocalInvocationIndex == 0u) {
      atomicAdd(tilesSkipped, 1u);
      atomicAdd(tilesConverged, 1u);
      atomicAdd(raysSaved, surfacePixels * max(pc.raysPerPixel, 1u));
    }
  } else if (gl_LocalInvocationIndex == 0u) {
    uint slot = atomicAdd(traceArgs[0], RB_SHADOW_TILE_SIZE) / RB_SHADOW_TILE_SIZE;
    tiles[slot] = gl_WorkGroupID.x | (gl_WorkGroupID.y << 16);
    atomicAdd(tilesTraced, 1u);
  }
}
