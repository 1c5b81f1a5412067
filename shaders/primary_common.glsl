// Shared by the first-trace shaders: the payload and the camera push constants.
#ifndef RAYBRIDGE_PRIMARY_COMMON_GLSL
#define RAYBRIDGE_PRIMARY_COMMON_GLSL

struct PrimaryPayload {
  float hitT;          // 0 = miss
  uint primitiveId;    // 0xFFFFFFFF = miss
  uint instanceIndex;  // gl_InstanceCustomIndexEXT
};

// The ray through pixel (x, y) counted from the top-left, through the pixel centre:
//   dir = normalize(forward + ndcX * right + ndcY * up), ndc in [-1, 1], +Y up.
// right and up are pre-scaled on the CPU by tan(fovY/2) (and the aspect ratio for right).
layout(push_constant) uniform PrimaryConstants {
  vec4 eye;      // xyz
  vec4 right;    // xyz
  vec4 up;       // xyz
  vec4 forward;  // xyz
  uvec2 size;
  float tMin;
  float tMax;
} pc;

#endif
