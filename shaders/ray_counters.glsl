// The ray counters every G-buffer pass adds the rays it traced to (read back by PassMetrics).
#ifndef RAYBRIDGE_RAY_COUNTERS_GLSL
#define RAYBRIDGE_RAY_COUNTERS_GLSL

#include "raybridge_shader_interface.glsl"

layout(set = 0, binding = RB_BINDING_RAY_COUNTERS) buffer RayCounters { uint rayCount[RB_RAY_COUNTER_SLOTS]; };

void rbCountRays(uvec2 pixel, uint rays) { atomicAdd(rayCount[RB_RAY_COUNTER_SLOT(pixel.x, pixel.y)], rays); }

#endif
