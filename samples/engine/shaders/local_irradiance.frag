#version 450
#extension GL_GOOGLE_include_directive : require
// Writes the engine's own KHR-light diffuse irradiance E per pixel (FrameParams::outputLocalLightIrradiance):
// shadow maps for the shadowed lights, unshadowed for the rest, the same function the lighting pass uses.
// The position is reconstructed (camera-relative) from the pre-pass depth; the cosine uses the pre-pass
// SHADING normal (normal-mapped, what the lighting shades with), the shadow lookup's offset the geometric one.
// Background: 0.
#include "frame_uniforms.glsl"
#include "screen_space.glsl"
#define LOCAL_LIGHT_SET 1
#define LOCAL_LIGHT_BINDING 3
#include "local_lights.glsl"

layout(set = 1, binding = 0) uniform sampler2D depthTex;
layout(set = 1, binding = 1) uniform sampler2D normalTex;           // shading normal
layout(set = 1, binding = 2) uniform sampler2D geometricNormalTex;  // triangle normal

layout(location = 0) out vec4 outIrradiance;

void main() {
  ivec2 pixel = ivec2(gl_FragCoord.xy);
  float depth = texelFetch(depthTex, pixel, 0).r;
  if (depth >= 1.0) {
    outIrradiance = vec4(0.0, 0.0, 0.0, 1.0);
    return;
  }
  vec3 position = eyeRelativeFromDepth(pixelUv(pixel), depth);
  vec3 n = normalize(texelFetch(normalTex, pixel, 0).xyz);
  vec3 ng = normalize(texelFetch(geometricNormalTex, pixel, 0).xyz);
  outIrradiance = vec4(localLightIrradiance(position, n, ng), 1.0);
}
