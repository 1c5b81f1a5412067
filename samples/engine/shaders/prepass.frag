#version 450
#extension GL_GOOGLE_include_directive : require
// Depth + normal pre-pass of OPAQUE and MASK draws (BLEND surfaces never enter it). Target 0: shading normal +
// roughness, target 1: geometric normal + metallic.
#include "common.glsl"
#include "surface.glsl"

layout(location = 0) out vec4 outNormalRoughness;
layout(location = 1) out vec4 outGeometricNormal;

void main() {
  Surface s = evaluateSurface();
  alphaTest(s);
  outNormalRoughness = vec4(s.n, s.roughness);
  outGeometricNormal = vec4(s.ng, s.metallic);
}
