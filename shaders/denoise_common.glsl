// Shared by the denoiser's compute shaders: push constants and G-buffer reconstruction.
#ifndef RAYBRIDGE_DENOISE_COMMON_GLSL
#define RAYBRIDGE_DENOISE_COMMON_GLSL

#include "raybridge_gbuffer.glsl"

// Mirrors rb::DenoiseConstants (sdk/src/denoiser.cpp); 224 bytes.
layout(push_constant) uniform DenoiseConstants {
  mat4 inverseProjection;
  vec4 viewToWorld[3];      // xyz columns; [0].w = w of the inverse projection at depth 1
  mat4 previousViewProjection;  // previous frame: camera-relative world -> clip (rotation-only view)
  vec4 cameraDelta;         // xyz: current camera position - previous camera position; w: depth sigma
  uvec4 size;               // x, y: size; z: flags (bit 0 reversed-Z, bit 1 octahedral, bit 2 history valid,
                            // bit 3 motion vectors); w: step (a-trous) or max history (temporal)
  vec4 params;              // x: normal power, y: rays per pixel of the signal (0 = unknown)
} pc;

const uint RB_DN_REVERSED_Z = 1u;
const uint RB_DN_OCTAHEDRAL = 2u;
const uint RB_DN_HISTORY = 4u;
const uint RB_DN_MOTION = 8u;

bool rbDnSky(float depth) { return (pc.size.z & RB_DN_REVERSED_Z) != 0u ? depth <= 0.0 : depth >= 1.0; }

vec3 rbDnCameraRelative(uvec2 pixel, float depth) {
  return rbReconstructCameraRelative(pixel, vec2(pc.size.xy), depth, pc.inverseProjection,
                                     mat3(pc.viewToWorld[0].xyz, pc.viewToWorld[1].xyz, pc.viewToWorld[2].xyz),
                                     pc.viewToWorld[0].w, (pc.size.z & RB_DN_REVERSED_Z) != 0u);
}

vec3 rbDnNormal(vec4 texel) { return rbDecodeNormal(texel, (pc.size.z & RB_DN_OCTAHEDRAL) != 0u ? 1u : 0u); }

#endif
