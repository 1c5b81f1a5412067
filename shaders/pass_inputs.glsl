// Inputs every G-buffer effect pass shares: push constants (camera, G-buffer layout, pass parameters) and the
// helpers to turn a pixel into a camera-relative surface point with a robust ray origin.
#ifndef RAYBRIDGE_PASS_INPUTS_GLSL
#define RAYBRIDGE_PASS_INPUTS_GLSL

#include "raybridge_gbuffer.glsl"
#include "raybridge_sampling.glsl"

// Mirrors rb::PassConstants (sdk/src/pass_constants.h); 208 bytes, under the 256-byte push constant limit.
layout(push_constant) uniform PassConstants {
  mat4 inverseProjection;
  vec4 viewToWorld[3];  // xyz: columns of the view-to-world rotation; [0].w: w of the inverse projection at depth 1
  vec4 cameraToTlas;    // xyz: camera position in the TLAS's space; w: depth quantum (0 = float ulp)
  uvec4 gbuffer;        // x: width, y: height, z: RB_GB_* flags, w: frame index (noise seed)
  vec4 p0;              // pass parameters
  vec4 p1;
  vec4 p2;
  uvec4 u0;
} pc;

const uint RB_GB_REVERSED_Z = 1u;
const uint RB_GB_OCTAHEDRAL = 2u;
const uint RB_GB_GEOMETRIC_NORMAL = 4u;
const uint RB_GB_ROUGHNESS_IN_NORMAL_W = 8u;
const uint RB_GB_ROUGHNESS_IMAGE = 16u;
const uint RB_GB_ALBEDO_IMAGE = 32u;

mat3 rbViewToWorld() { return mat3(pc.viewToWorld[0].xyz, pc.viewToWorld[1].xyz, pc.viewToWorld[2].xyz); }

bool rbIsSky(float depth) {
  return (pc.gbuffer.z & RB_GB_REVERSED_Z) != 0u ? depth <= 0.0 : depth >= 1.0;
}

uint rbNormalEncoding() { return (pc.gbuffer.z & RB_GB_OCTAHEDRAL) != 0u ? 1u : 0u; }

vec3 rbCameraRelative(uvec2 pixel, float depth) {
  return rbReconstructCameraRelative(pixel, vec2(pc.gbuffer.xy), depth, pc.inverseProjection, rbViewToWorld(),
                                     pc.viewToWorld[0].w, (pc.gbuffer.z & RB_GB_REVERSED_Z) != 0u);
}

// The surface point of `pixel` in TLAS space.
vec3 rbSurfacePoint(uvec2 pixel, float depth) { return pc.cameraToTlas.xyz + rbCameraRelative(pixel, depth); }

// A ray origin off the surface: along the geometric normal (turned towards the viewer) by a margin that
// covers the reconstruction error of a depth-buffer position, then by the float-precision offset.
vec3 rbRayOrigin(uvec2 pixel, float depth, vec3 geometricNormal, out vec3 facingNormal) {
  vec3 p = rbCameraRelative(pixel, depth);
  // One depth quantum further away: the distance between the two reconstructions is the position error.
  float quantum = pc.cameraToTlas.w > 0.0 ? pc.cameraToTlas.w
                                          : abs(uintBitsToFloat(floatBitsToUint(depth) + 1u) - depth);
  float stepDepth = (pc.gbuffer.z & RB_GB_REVERSED_Z) != 0u ? depth - quantum : depth + quantum;
  vec3 q = rbCameraRelative(pixel, stepDepth);
  float error = length(q - p);
  facingNormal = dot(geometricNormal, p) > 0.0 ? -geometricNormal : geometricNormal;
  vec3 origin = pc.cameraToTlas.xyz + p + facingNormal * (16.0 * error + 1e-5 * length(p));
  return rbOffsetRayOrigin(origin, facingNormal);
}

#endif
