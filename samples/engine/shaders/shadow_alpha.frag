#version 450
#extension GL_GOOGLE_include_directive : require
// Alpha test of the shadow map, alpha = baseColorFactor.a * base colour texture alpha (as surface.glsl).
// MASK casts where alpha >= alphaCutoff, like the camera passes. BLEND casts with probability alpha: a hashed
// test against a per-texel threshold, uniform in (0, 1], of the shadow-map texel and the instance (stable from
// frame to frame, independent between stacked surfaces), so the PCF-filtered shadow passes 1 - alpha of the
// light in the mean, as the SDK's stochastic any-hit test does.
#include "common.glsl"

layout(set = 1, binding = 0) uniform sampler2D baseColorTex;

layout(location = 0) in vec2 inUv;

// Jarzynski and Olano, "Hash Functions for GPU Rendering" (JCGT 2020): pcg3d.
uvec3 pcg3d(uvec3 v) {
  v = v * 1664525u + 1013904223u;
  v.x += v.y * v.z;
  v.y += v.z * v.x;
  v.z += v.x * v.y;
  v ^= v >> 16u;
  v.x += v.y * v.z;
  v.y += v.z * v.x;
  v.z += v.x * v.y;
  return v;
}

void main() {
  float alpha = draw.baseColorFactor.a * texture(baseColorTex, inUv).a;
  float threshold = draw.alphaCutoff;
  if (draw.alphaMode == SE_ALPHA_BLEND)
    threshold = (float(pcg3d(uvec3(gl_FragCoord.xy, draw.instance)).x >> 8u) + 1.0) * (1.0 / 16777216.0);
  if (alpha < threshold) discard;
}
