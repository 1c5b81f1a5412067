// Shared declarations of the scene passes. Keep in sync with FrameUniforms / DrawConstants in
// src/pipelines.h (sizes and offsets are static_asserted there).
#include "frame_uniforms.glsl"

// DrawConstants::alphaMode: Material::alphaMode (AlphaMode in scene.h, static_asserted in src/pipelines.h).
#define SE_ALPHA_OPAQUE 0u
#define SE_ALPHA_MASK 1u
#define SE_ALPHA_BLEND 2u

layout(push_constant) uniform DrawConstants {
  mat4 model;  // instance-local -> camera-relative (world - eye)
  vec4 baseColorFactor;
  vec4 material;      // x: metallic, y: perceptual roughness, z: normal scale, w: occlusion strength (0 = none)
  vec3 emissive;      // linear radiance factor
  uint alphaMode;     // SE_ALPHA_*
  float alphaCutoff;  // SE_ALPHA_MASK: covered where alpha >= alphaCutoff
  uint instance;      // Scene::instances index: seeds the hashed shadow-map test of SE_ALPHA_BLEND draws
  // Device address of last frame's model matrices (mat4 per Scene::instances entry, rebased to this frame's eye),
  // read by mesh.vert for the pre-pass's motion vectors; (0, 0) = none (the probe capture, no bufferDeviceAddress):
  // the instance is taken as still.
  uvec2 previousModels;
} draw;
