// Shared by the first-trace shaders: the payload and the camera push constants.
#ifndef RAYBRIDGE_PRIMARY_COMMON_GLSL
#define RAYBRIDGE_PRIMARY_COMMON_GLSL

struct PrimaryPayload {
  float hitT;          // 0 = miss
  uint primitiveId;    // 0xFFFFFFFF = miss
  uint instanceIndex;  // gl_InstanceCustomIndexEXT
};

#include "raybridge_pass_constants.glsl"
layout(push_constant) uniform PrimaryPushConstants { PrimaryConstants pc; };

#endif
