// Changes a reflection shows (ReflectionSettings::changedBoxes and relitBoxes): whether a reflection ray met a box
// where the world changed since the last frame, so that the pixel's history is stale (a = 2: the Denoiser starts it
// afresh). Include after the pass's push constant block (ReflectionConstants pc).
#ifndef RAYBRIDGE_REFLECTION_CHANGES_GLSL
#define RAYBRIDGE_REFLECTION_CHANGES_GLSL

#extension GL_EXT_buffer_reference : require
#extension GL_EXT_buffer_reference_uvec2 : require

#include "segment_box.glsl"

// Mirrors rb::ReflectionChangedBox (reflection_pass.cpp): 32 bytes, in the TLAS's space.
struct RbReflectionChangedBox {
  vec3 lo;
  uint relit;  // 0: geometry changed inside (the ray's path and the hit's sun ray are tested); 1: lighting only
  vec3 hi;
  float pad;
};
layout(buffer_reference, std430, buffer_reference_align = 16) readonly buffer RbReflectionChangedBoxes {
  RbReflectionChangedBox b[];
};

// A reflection ray from `origin` along unit `dir` that hit at distance hitT (< 0: it escaped to the sky): does what
// it shows lie in a change? Its path crossing a geometry box (something moved into or out of it), the hit's ray to
// the sun `toSun` crossing one (a moved object's shadow on what the mirror shows), or the hit inside a relit box.
bool rbReflectionChanged(vec3 origin, vec3 dir, float hitT, vec3 toSun) {
  RbReflectionChangedBoxes boxes = RbReflectionChangedBoxes(pc.changedBoxes);
  const bool hit = hitT >= 0.0;
  const vec3 p = origin + dir * (hit ? hitT : 0.0);
  const bool sun = hit && dot(toSun, toSun) > 0.0;
  for (uint i = 0u; i < pc.changedBoxCount; ++i) {
    const RbReflectionChangedBox b = boxes.b[i];
    if (b.relit != 0u) {
      if (hit && all(greaterThanEqual(p, b.lo)) && all(lessThanEqual(p, b.hi))) return true;
      continue;
    }
    if (rbSegmentHitsBox(origin, dir, hit ? hitT : 1e30, b.lo, b.hi)) return true;
    if (sun && rbSegmentHitsBox(p, toSun, 1e30, b.lo, b.hi)) return true;
  }
  return false;
}

#endif
