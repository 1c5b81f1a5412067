#version 450
#extension GL_GOOGLE_include_directive : require
// Vertex shader shared by the pre-pass and the lighting pass: one module and identical vertex input
// guarantee bit-identical depth, which the lighting pass's EQUAL depth test relies on. draw.model is rebased
// to the eye on the host, so positions are camera-relative (world axes) and keep float precision far from
// the world origin.
#include "common.glsl"

layout(location = 0) in vec3 inPosition;
layout(location = 1) in vec3 inNormal;
layout(location = 2) in vec2 inUv;
layout(location = 3) in vec4 inTangent;

layout(location = 0) out vec3 outEyeRelativePos;  // world position - eye
layout(location = 1) out vec3 outNormal;
layout(location = 2) out vec2 outUv;
layout(location = 3) out vec4 outTangent;

invariant gl_Position;

void main() {
  vec4 position = draw.model * vec4(inPosition, 1.0);
  outEyeRelativePos = position.xyz;
  outNormal = transpose(inverse(mat3(draw.model))) * inNormal;
  outTangent = vec4(mat3(draw.model) * inTangent.xyz, inTangent.w);
  outUv = inUv;
  gl_Position = frame.viewProj * position;
}
