#version 460
#extension GL_EXT_ray_tracing : require
#extension GL_GOOGLE_include_directive : require
// A reflection ray that escapes sees the sky.
#include "raybridge_pass_constants.glsl"
layout(push_constant) uniform ReflectionPushConstants { ReflectionConstants pc; };

#include "reflection_payload.glsl"
layout(location = 0) rayPayloadInEXT ReflectionPayload payload;

void main() { payload.radiance = pc.skyRadiance; }
