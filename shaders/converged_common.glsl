// What the converged-tile dispatches of every pass share (shadow_converged.glsl, rgb_converged.glsl): the
// push constants (the denoiser's reprojection, as `pc`, then the test's settings, as `tc`), one workgroup per
// 8x8-pixel tile, the G-buffer's depth and motion, and the tile state.
#ifndef RAYBRIDGE_CONVERGED_COMMON_GLSL
#define RAYBRIDGE_CONVERGED_COMMON_GLSL

#include "raybridge_pass_constants.glsl"
layout(push_constant) uniform ConvergedPushConstants { ConvergedTileConstants tc; };
#define pc tc.denoise
#define RB_DN_PUSH_CONSTANTS_DECLARED 1
#include "denoise_common.glsl"

layout(local_size_x = RB_SHADOW_TILE_SIZE, local_size_y = RB_SHADOW_TILE_SIZE) in;
layout(set = 0, binding = RB_CONVERGED_BINDING_DEPTH) uniform sampler2D gDepth;
layout(set = 0, binding = RB_CONVERGED_BINDING_MOTION) uniform sampler2D gMotion;  // pixels, current - previous
layout(set = 0, binding = RB_CONVERGED_BINDING_REACTIVE) uniform sampler2D gReactive;
layout(set = 0, binding = RB_CONVERGED_BINDING_STATE, std430) buffer TileState { uint tileState[]; };

// The tile's index in the state buffer, row by row: the pass's classifier (shadows, AO) numbers its workgroups the
// same way, and the reflection pass's ray generation shader computes it from the pixel (reflection_raygen.glsl).
uint rbConvergedTile() { return gl_WorkGroupID.x + gl_WorkGroupID.y * gl_NumWorkGroups.x; }

#endif
