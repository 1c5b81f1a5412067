#version 450
#extension GL_GOOGLE_include_directive : require
// Depth-only shadow-map pass of OPAQUE draws (no fragment shader), positions only; MASK and BLEND draws take
// shadow_alpha.vert/.frag. draw.model and frame.lightViewProj are both camera-relative.
#include "common.glsl"

layout(location = 0) in vec3 inPosition;

void main() { gl_Position = frame.lightViewProj * draw.model * vec4(inPosition, 1.0); }
