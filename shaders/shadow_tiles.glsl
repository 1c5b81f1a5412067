// The shadow pass's tile list: written by its classifier (shadow_classify.glsl), read by its ray generation shader
// (shadow_raygen.glsl), launched by vkCmdTraceRaysIndirectKHR from the arguments at its start. The AO pass's
// (ao_classify.comp, ao_raygen.glsl) is the same, at the same binding.
#ifndef RAYBRIDGE_SHADOW_TILES_GLSL
#define RAYBRIDGE_SHADOW_TILES_GLSL

#include "raybridge_shader_interface.glsl"

// traceArgs is a VkTraceRaysIndirectCommandKHR: width = 8 per listed tile (the classifier adds them), height = 8
// rows, depth 1. tiles: tile x | tile y << 16, in no particular order.
layout(set = 0, binding = RB_SHADOW_BINDING_TILES, std430) buffer ShadowTiles {  // = RB_AO_BINDING_TILES
  uint traceArgs[RB_SHADOW_TILE_HEADER_UINTS];
  uint tiles[];
};

// The pixel a launch over the tile list traces: 8 launch columns per tile, one row of the tile per launch row.
uvec2 rbShadowListedPixel(uvec2 launch) {
  uint tile = tiles[launch.x / RB_SHADOW_TILE_SIZE];
  return uvec2(tile & 0xFFFFu, tile >> 16) * RB_SHADOW_TILE_SIZE + uvec2(launch.x % RB_SHADOW_TILE_SIZE, launch.y);
}

#endif
