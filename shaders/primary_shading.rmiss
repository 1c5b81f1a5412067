#version 460
#extension GL_EXT_ray_tracing : require
#extension GL_GOOGLE_include_directive : require
// A primary ray that hits nothing sees the sky.
#include "primary_shading_common.glsl"

layout(location = 0) rayPayloadInEXT PrimaryShadingPayload payload;

void main() {
  payload.radiance = pc.skyRadiance;
  payload.hitT = 0.0;
}
