// Raybridge G-buffer helpers, shared by the engine (to write) and the SDK passes (to read), so both sides
// encode exactly the same thing. Include from GLSL 4.5+; no bindings are declared here.
#ifndef RAYBRIDGE_GBUFFER_GLSL
#define RAYBRIDGE_GBUFFER_GLSL

// Octahedral normal encoding (NormalEncoding::Octahedral): unit vector -> [-1, 1]^2.
vec2 rbSignNotZero(vec2 v) { return vec2(v.x >= 0.0 ? 1.0 : -1.0, v.y >= 0.0 ? 1.0 : -1.0); }

vec2 rbEncodeOctahedral(vec3 n) {
  n /= abs(n.x) + abs(n.y) + abs(n.z);
  return n.z >= 0.0 ? n.xy : (1.0 - abs(n.yx)) * rbSignNotZero(n.xy);
}

vec3 rbDecodeOctahedral(vec2 e) {
  vec3 n = vec3(e, 1.0 - abs(e.x) - abs(e.y));
  if (n.z < 0.0) n.xy = (1.0 - abs(n.yx)) * rbSignNotZero(n.xy);
  return normalize(n);
}

// Decodes a G-buffer normal texel. encoding: 0 = WorldFloat (xyz), 1 = Octahedral (xy).
vec3 rbDecodeNormal(vec4 texel, uint encoding) {
  return encoding == 1u ? rbDecodeOctahedral(texel.xy) : normalize(texel.xyz);
}

// Camera-relative world position of a pixel: view-space position from depth through the inverse projection,
// rotated into world axes (no translation: add the camera position in double precision on the CPU side).
//   pixel: integer pixel coordinates (top-left origin); size: G-buffer size; depth: raw depth-buffer value.
// With standard depth (near 1 far away) w = a * depth + b cancels almost completely; pass
// wAtDepthOne = a + b (computed in double on the CPU) and w is formed as wAtDepthOne + a * (depth - 1), where
// depth - 1 is exact. With reversed-Z pass reversedZ = true: the direct form has no cancellation there.
// rbReconstructViewPosition: the same point in view space (before the rotation into world axes).
vec3 rbReconstructViewPosition(uvec2 pixel, vec2 size, float depth, mat4 inverseProjection, float wAtDepthOne,
                               bool reversedZ) {
  vec2 ndc = (vec2(pixel) + 0.5) / size * 2.0 - 1.0;
  vec3 xyz = (inverseProjection * vec4(ndc, depth, 1.0)).xyz;
  float wxy = inverseProjection[0][3] * ndc.x + inverseProjection[1][3] * ndc.y;
  float w = reversedZ ? wxy + inverseProjection[2][3] * depth + inverseProjection[3][3]
                      : wxy + (wAtDepthOne + inverseProjection[2][3] * (depth - 1.0));
  return xyz / w;
}

vec3 rbReconstructCameraRelative(uvec2 pixel, vec2 size, float depth, mat4 inverseProjection, mat3 viewToWorld,
                                 float wAtDepthOne, bool reversedZ) {
  return viewToWorld * rbReconstructViewPosition(pixel, size, depth, inverseProjection, wAtDepthOne, reversedZ);
}

#endif
