#version 460
#extension GL_EXT_ray_tracing : require
#extension GL_GOOGLE_include_directive : require
#include "primary_common.glsl"

layout(location = 0) rayPayloadInEXT PrimaryPayload payload;

void main() {
  payload.hitT = 0.0;
  payload.primitiveId = 0xFFFFFFFFu;
  payload.instanceIndex = 0xFFFFFFFFu;
}
