// Shared declarations of the scene passes. Keep in sync with FrameUniforms / DrawConstants in
// src/pipelines.h.

layout(set = 0, binding = 0) uniform FrameUniforms {
  mat4 view;
  mat4 proj;
  mat4 viewProj;
  mat4 invViewProj;
  mat4 lightViewProj;
  vec4 cameraPos;     // xyz
  vec4 sunDirection;  // xyz: towards the sun, normalized
  vec4 sunRadiance;   // rgb: color * intensity
  vec4 sky;           // rgb: sky radiance (background), w: ambient intensity
  vec4 viewport;      // width, height, 1/width, 1/height
  vec4 shadow;        // x: 1/map size, y: PCF taps per axis, z: normal offset (world units)
  uvec4 inputs;       // x: external sun visibility, y: external AO, z: external reflection (1 = bound)
} frame;

layout(push_constant) uniform DrawConstants {
  mat4 model;
  vec4 baseColorFactor;
  vec4 material;  // x: metallic, y: perceptual roughness, z: normal scale
  vec4 emissive;  // rgb
} draw;
