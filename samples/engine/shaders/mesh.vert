#version 450
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_buffer_reference : require
#extension GL_EXT_buffer_reference_uvec2 : require
// Vertex shader shared by the pre-pass and the lighting pass: one module and identical vertex input
// guarantee bit-identical depth, which the lighting pass's EQUAL depth test relies on. draw.model is rebased
// to the eye on the host, so positions are camera-relative (world axes) and keep float precision far from
// the world origin.
#include "common.glsl"

layout(location = 0) in vec3 inPosition;
layout(location = 1) in vec3 inNormal;
layout(location = 2) in vec2 inUv;
layout(location = 3) in vec4 inTangent;
// Last frame's position of this vertex, instance-local: the deformed buffer of the previous frame for a skinned or
// morphed instance, else the same buffer as inPosition.
layout(location = 4) in vec3 inPreviousPosition;

layout(location = 0) out vec3 outEyeRelativePos;  // world position - eye
layout(location = 1) out vec3 outNormal;
layout(location = 2) out vec2 outUv;
layout(location = 3) out vec4 outTangent;
// This frame's and last frame's clip positions of the vertex, for the pre-pass's motion vectors (prepass.frag). A
// vertex whose position, model matrix and camera did not change gets this frame's twice, so its motion is exactly 0
// (evaluating last frame's with the same inputs may round differently: NVIDIA's compiler fuses it differently).
layout(location = 4) out vec4 outCurrentClip;
layout(location = 5) out vec4 outPreviousClip;

layout(buffer_reference, std430, buffer_reference_align = 16) readonly buffer PreviousModels { mat4 models[]; };

invariant gl_Position;

void main() {
  vec4 position = draw.model * vec4(inPosition, 1.0);
  outEyeRelativePos = position.xyz;
  outNormal = transpose(inverse(mat3(draw.model))) * inNormal;
  outTangent = vec4(mat3(draw.model) * inTangent.xyz, inTangent.w);
  outUv = inUv;
  gl_Position = frame.viewProj * position;
  mat4 previousModel = draw.model;
  if (draw.previousModels != uvec2(0)) previousModel = PreviousModels(draw.previousModels).models[draw.instance];
  outCurrentClip = gl_Position;
  const bool still = inPreviousPosition == inPosition && previousModel == draw.model &&
                     frame.previousViewProj == frame.viewProj;
  outPreviousClip = still ? outCurrentClip : frame.previousViewProj * (previousModel * vec4(inPreviousPosition, 1.0));
}
