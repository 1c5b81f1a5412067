// Shared declarations of the scene passes. Keep in sync with FrameUniforms / DrawConstants in
// src/pipelines.h.
#include "frame_uniforms.glsl"

layout(push_constant) uniform DrawConstants {
  mat4 model;
  vec4 baseColorFactor;
  vec4 material;  // x: metallic, y: perceptual roughness, z: normal scale
  vec4 emissive;  // rgb
} draw;
