#version 460
#extension GL_EXT_ray_tracing : require
#extension GL_GOOGLE_include_directive : require
#include "primary_common.glsl"

layout(location = 0) rayPayloadInEXT PrimaryPayload payload;

void main() {
  payload.hitT = gl_HitTEXT;
  payload.primitiveId = uint(gl_PrimitiveID);
  payload.instanceIndex = uint(gl_InstanceCustomIndexEXT);
}
