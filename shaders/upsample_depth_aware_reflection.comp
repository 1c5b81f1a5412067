#version 460
#extension GL_GOOGLE_include_directive : require
// The depth-aware upsample of half-resolution reflections: RGBA16F radiance, a = coverage (see
// upsample_depth_aware.glsl).
#define RB_UPSAMPLE_REFLECTION
#include "upsample_depth_aware.glsl"
