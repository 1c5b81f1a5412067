#version 460
#extension GL_GOOGLE_include_directive : require
// The depth-aware upsample of half-resolution AO: R16F open fraction (see upsample_depth_aware.glsl).
#include "upsample_depth_aware.glsl"
