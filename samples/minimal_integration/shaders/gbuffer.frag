// Writes the G-buffer Raybridge reads: octahedral world normals (RG16_SNORM) and motion vectors in pixels,
// current - previous (RG16_SFLOAT); depth is the rasterizer's reversed-Z.
#version 450
#extension GL_GOOGLE_include_directive : require

#include "raybridge_gbuffer.glsl"

layout(location = 0) in vec3 worldPosition;
layout(location = 1) in vec3 previousPixel;

layout(location = 0) out vec2 outNormal;
layout(location = 1) out vec2 outMotion;

void main() {
  // The face normal from the world position's derivatives, flat per triangle: the geometric normal, which the
  // conformance test compares against. Framebuffer x runs right and y down, so cross(dy, dx) faces the viewer.
  vec3 n = normalize(cross(dFdy(worldPosition), dFdx(worldPosition)));
  outNormal = rbEncodeOctahedral(n);
  outMotion = gl_FragCoord.xy - previousPixel.xy / previousPixel.z;
}
