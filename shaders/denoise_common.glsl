// Shared by the denoiser's compute shaders: push constants and G-buffer reconstruction.
#ifndef RAYBRIDGE_DENOISE_COMMON_GLSL
#define RAYBRIDGE_DENOISE_COMMON_GLSL

#include "raybridge_gbuffer.glsl"

#include "raybridge_pass_constants.glsl"
layout(push_constant) uniform DenoisePushConstants { DenoiseConstants pc; };

bool rbDnSky(float depth) { return (pc.flags & RB_DN_REVERSED_Z) != 0u ? depth <= 0.0 : depth >= 1.0; }

vec3 rbDnCameraRelative(uvec2 pixel, float depth) {
  return rbReconstructCameraRelative(pixel, vec2(pc.size), depth, pc.inverseProjection, pc.viewToWorld,
                                     pc.wAtDepthOne, (pc.flags & RB_DN_REVERSED_Z) != 0u);
}

// The view-space position: what the a-trous taps compare (against the centre's normal turned into view space),
// which saves each tap the rotation into world axes.
vec3 rbDnViewPosition(uvec2 pixel, float depth) {
  return rbReconstructViewPosition(pixel, vec2(pc.size), depth, pc.inverseProjection, pc.wAtDepthOne,
                                   (pc.flags & RB_DN_REVERSED_Z) != 0u);
}

vec3 rbDnNormal(vec4 texel) { return rbDecodeNormal(texel, (pc.flags & RB_DN_OCTAHEDRAL) != 0u ? 1u : 0u); }

#endif
