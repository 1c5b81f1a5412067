#version 450
#extension GL_GOOGLE_include_directive : require
// Shadow-map pass of MASK and BLEND draws: positions plus the UVs shadow_alpha.frag alpha-tests with (opaque
// draws take shadow.vert, positions only). draw.model and frame.lightViewProj are both camera-relative.
#include "common.glsl"

layout(location = 0) in vec3 inPosition;
layout(location = 2) in vec2 inUv;

layout(location = 0) out vec2 outUv;

void main() {
  outUv = inUv;
  gl_Position = frame.lightViewProj * draw.model * vec4(inPosition, 1.0);
}
