// The slab test of a segment against an axis-aligned box, shared by the change masks (change_masks.comp: a shadow ray
// through a changed box) and the reflections' change test (reflection_changes.glsl: a reflection ray's path).
#ifndef RAYBRIDGE_SEGMENT_BOX_GLSL
#define RAYBRIDGE_SEGMENT_BOX_GLSL

// Whether the segment p + t d, t in [0, tMax], meets the box [lo, hi]. A zero component of d (the default sun,
// straight up) becomes a tiny one: an infinite inverse times a zero distance would be NaN, and min/max of NaN is not
// defined.
bool rbSegmentHitsBox(vec3 p, vec3 d, float tMax, vec3 lo, vec3 hi) {
  vec3 inv = 1.0 / mix(d, vec3(1e-20), lessThan(abs(d), vec3(1e-20)));
  vec3 t0 = (lo - p) * inv, t1 = (hi - p) * inv;
  vec3 tn = min(t0, t1), tf = max(t0, t1);
  float enter = max(max(tn.x, tn.y), max(tn.z, 0.0));
  float leave = min(min(tf.x, tf.y), min(tf.z, tMax));
  return enter <= leave;
}

#endif
