// Half-resolution tracing, shared by the passes that trace at half resolution (ao.rgen, reflect.rgen) and the
// upsample that reads their samples (upsample_depth_aware.glsl): which G-buffer pixel each sample stands for.
#ifndef RAYBRIDGE_HALF_RESOLUTION_GLSL
#define RAYBRIDGE_HALF_RESOLUTION_GLSL

#include "raybridge_shader_interface.glsl"

// The half-resolution image of a full-resolution size: one sample per 2x2 block, a partial block included.
uvec2 rbHalfResSize(uvec2 size) { return (size + 1u) / 2u; }

// This frame's corner of every 2x2 block (RB_HALF_RES_OFFSET_*): the same in every block, so the samples form a
// regular grid the upsample can weight bilinearly, and a different one each frame, so a temporal filter sees every
// pixel traced within 4 frames.
uvec2 rbHalfResOffset(uint frame) { return uvec2(RB_HALF_RES_OFFSET_X(frame), RB_HALF_RES_OFFSET_Y(frame)); }

// The G-buffer pixel that sample `cell` traces for in `frame`, clamped to a `size` image (odd sizes: the last
// column and row are blocks of one pixel).
uvec2 rbHalfResTracedPixel(uvec2 cell, uint frame, uvec2 size) {
  return min(2u * cell + rbHalfResOffset(frame), size - 1u);
}

#endif
