#version 450
#extension GL_GOOGLE_include_directive : require
// Writes the lighting pass's shadow-map sun visibility per pixel (1 = lit, background = 1) so applications
// can read the engine's own shadows back, e.g. to compare them with a ray-traced reference. The position is
// reconstructed (camera-relative) from the pre-pass depth; normals come from the pre-pass.
#include "frame_uniforms.glsl"
#include "screen_space.glsl"
#include "shadow_sampling.glsl"

layout(set = 1, binding = 0) uniform sampler2D depthTex;
layout(set = 1, binding = 1) uniform sampler2D normalTex;           // shading normal
layout(set = 1, binding = 2) uniform sampler2D geometricNormalTex;  // triangle normal
layout(set = 1, binding = 3) uniform sampler2DShadow shadowMap;

layout(location = 0) out float outVisibility;

void main() {
  ivec2 pixel = ivec2(gl_FragCoord.xy);
  float depth = texelFetch(depthTex, pixel, 0).r;
  if (depth >= 1.0) {
    outVisibility = 1.0;
    return;
  }
  vec3 position = eyeRelativeFromDepth(pixelUv(pixel), depth);
  vec3 n = normalize(texelFetch(normalTex, pixel, 0).xyz);
  vec3 ng = normalize(texelFetch(geometricNormalTex, pixel, 0).xyz);
  outVisibility = sunVisibility(shadowMap, position, n, ng);
}
