// What every G-buffer effect pass shares: the helpers that turn a pixel into a camera-relative surface point
// with a robust ray origin. They read `pc.gbuffer` (GBufferConstants, raybridge_pass_constants.glsl): include
// this after the pass's push constant block.
#ifndef RAYBRIDGE_PASS_INPUTS_GLSL
#define RAYBRIDGE_PASS_INPUTS_GLSL

#include "raybridge_gbuffer.glsl"
#include "raybridge_sampling.glsl"
#include "raybridge_shader_interface.glsl"

bool rbIsSky(float depth) {
  return (pc.gbuffer.flags & RB_GB_REVERSED_Z) != 0u ? depth <= 0.0 : depth >= 1.0;
}

uint rbNormalEncoding() { return (pc.gbuffer.flags & RB_GB_OCTAHEDRAL) != 0u ? 1u : 0u; }

// The roughness the G-buffer holds for `pixel`: normal.w (RB_GB_ROUGHNESS_IN_NORMAL_W) or the r of the roughness
// image (RB_GB_ROUGHNESS_IMAGE); 1 without either. `normalTexel`: the pixel's normal texel.
float rbRoughness(vec4 normalTexel, sampler2D roughnessMetalness, ivec2 pixel) {
  return (pc.gbuffer.flags & RB_GB_ROUGHNESS_IN_NORMAL_W) != 0u ? normalTexel.w
         : (pc.gbuffer.flags & RB_GB_ROUGHNESS_IMAGE) != 0u    ? texelFetch(roughnessMetalness, pixel, 0).x
                                                                 : 1.0;
}

vec3 rbCameraRelative(uvec2 pixel, float depth) {
  return rbReconstructCameraRelative(pixel, vec2(pc.gbuffer.size), depth, pc.gbuffer.inverseProjection,
                                     pc.gbuffer.viewToWorld, pc.gbuffer.wAtDepthOne,
                                     (pc.gbuffer.flags & RB_GB_REVERSED_Z) != 0u);
}

// The surface point of `pixel` in TLAS space.
vec3 rbSurfacePoint(uvec2 pixel, float depth) { return pc.gbuffer.cameraToTlas + rbCameraRelative(pixel, depth); }

// A ray origin off the surface: along the geometric normal (turned towards the viewer) by a margin that
// covers the reconstruction error of a depth-buffer position, then by the float-precision offset.
vec3 rbRayOrigin(uvec2 pixel, float depth, vec3 geometricNormal, out vec3 facingNormal) {
  vec3 p = rbCameraRelative(pixel, depth);
  // One depth quantum further away: the distance between the two reconstructions is the position error.
  float quantum = pc.gbuffer.depthQuantum > 0.0 ? pc.gbuffer.depthQuantum
                                                   : abs(uintBitsToFloat(floatBitsToUint(depth) + 1u) - depth);
  float stepDepth = (pc.gbuffer.flags & RB_GB_REVERSED_Z) != 0u ? depth - quantum : depth + quantum;
  vec3 q = rbCameraRelative(pixel, stepDepth);
  float error = length(q - p);
  facingNormal = dot(geometricNormal, p) > 0.0 ? -geometricNormal : geometricNormal;
  vec3 origin = pc.gbuffer.cameraToTlas + p + facingNormal * (16.0 * error + 1e-5 * length(p));
  return rbOffsetRayOrigin(origin, facingNormal);
}

#endif
