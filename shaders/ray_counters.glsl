// The ray counters every G-buffer pass adds the rays it traced to, the any-hit invocations its rays ran and, for a
// pass with a tile classifier, the tiles it traced and skipped, and of those skipped, the converged ones and the rays
// they saved (read back by PassMetrics).
#ifndef RAYBRIDGE_RAY_COUNTERS_GLSL
#define RAYBRIDGE_RAY_COUNTERS_GLSL

#include "raybridge_shader_interface.glsl"

// A shader whose set 0 numbers its bindings otherwise (rgb_converged.comp) defines RB_RAY_COUNTERS_BINDING.
#ifndef RB_RAY_COUNTERS_BINDING
#define RB_RAY_COUNTERS_BINDING RB_BINDING_RAY_COUNTERS
#endif
layout(set = 0, binding = RB_RAY_COUNTERS_BINDING) buffer RayCounters {
  uint rayCount[RB_RAY_COUNTER_SLOTS];
  uint anyHitCount[RB_RAY_COUNTER_SLOTS];
  uint tilesTraced;
  uint tilesSkipped;
  uint tilesConverged;
  uint raysSaved;
};

void rbCountRays(uvec2 pixel, uint rays) { atomicAdd(rayCount[RB_RAY_COUNTER_SLOT(pixel.x, pixel.y)], rays); }

void rbCountAnyHit(uvec2 pixel) { atomicAdd(anyHitCount[RB_RAY_COUNTER_SLOT(pixel.x, pixel.y)], 1u); }

#endif
