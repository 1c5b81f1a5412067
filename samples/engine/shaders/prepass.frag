#version 450
#extension GL_GOOGLE_include_directive : require
// Depth + normal pre-pass of OPAQUE and MASK draws (BLEND surfaces never enter it). Target 0: shading normal +
// roughness, target 1: geometric normal + metallic, target 2: motion vectors.
#include "common.glsl"
#include "surface.glsl"

layout(location = 0) out vec4 outNormalRoughness;
layout(location = 1) out vec4 outGeometricNormal;
// Screen-space motion in pixels, this frame's position - last frame's (camera, instance transform and deformation
// together). A point behind last frame's camera has no previous pixel: it gets kNoPreviousPixel, which sends any
// reprojection off screen (a disocclusion).
layout(location = 2) out vec2 outMotion;
layout(location = 4) in vec4 inCurrentClip;
layout(location = 5) in vec4 inPreviousClip;

const float kNoPreviousPixel = 32768.0;

vec2 pixelOf(vec4 clip) { return (clip.xy / clip.w * 0.5 + 0.5) * frame.viewport.xy; }

void main() {
  Surface s = evaluateSurface();
  alphaTest(s);
  outNormalRoughness = vec4(s.n, s.roughness);
  outGeometricNormal = vec4(s.ng, s.metallic);
  if (inPreviousClip == inCurrentClip) outMotion = vec2(0.0);  // still: exactly, whatever the divisions round to
  else outMotion = inPreviousClip.w > 0.0 ? pixelOf(inCurrentClip) - pixelOf(inPreviousClip) : vec2(kNoPreviousPixel);
}
