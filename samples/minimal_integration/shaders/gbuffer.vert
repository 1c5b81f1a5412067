// The minimal integration's G-buffer pass: world-space triangles through the current camera, and the
// previous frame's pixel position of each vertex for the motion vectors.
#version 450

layout(location = 0) in vec3 position;  // world space (the scene's instances are identity transforms)

layout(push_constant) uniform GBufferConstants {
  mat4 viewProjection;          // current frame, reversed-Z
  mat4 previousPixelFromWorld;  // previous frame's viewport * projection * view: clip with xy in pixels
} constants;

layout(location = 0) out vec3 worldPosition;
layout(location = 1) out vec3 previousPixel;  // xy / z = previous pixel position

void main() {
  worldPosition = position;
  previousPixel = (constants.previousPixelFromWorld * vec4(position, 1.0)).xyw;
  gl_Position = constants.viewProjection * vec4(position, 1.0);
}
