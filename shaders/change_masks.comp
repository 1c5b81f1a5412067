#version 460
#extension GL_EXT_buffer_reference : require
#extension GL_EXT_buffer_reference_uvec2 : require
#extension GL_GOOGLE_include_directive : require
// HybridEffects' change masks: per effect, the pixels whose value the frame's known changes can have changed, where
// that effect's denoiser (and its converged tiles and adaptive rays, which read the same mask) start afresh. The
// changes are world-space boxes the host found (sdk/src/frontend/change_tracker.h): the old and new box of each
// instance that moved, appeared, vanished or deformed, the old and new reach of each local light that changed, and
// the engine's own. A pixel's surface point P is changed for
//   - every effect: where P lies in a box (the object's own surface: its lighting moved with it);
//   - shadows: where the ray from P to the shadow light crosses a box (the object's old and new shadow), the box
//     widened by the light's spread (soft shadows' rays leave P in a cone);
//   - AO: where P lies within the AO range of a box (the contact shadow the object leaves and brings).
// Local-light boxes (RB_CHANGE_LOCAL_LIGHTS only) are a light's range: where it can light, it lit differently.
// The engine's reactive mask is set in every mask. Each mask is 1 (changed) or 0.
#include "raybridge_gbuffer.glsl"
#include "raybridge_pass_constants.glsl"

layout(push_constant) uniform ChangeMaskPushConstants { ChangeMaskConstants pc; };
layout(local_size_x = 8, local_size_y = 8) in;
layout(set = 0, binding = RB_CHANGE_BINDING_DEPTH) uniform sampler2D gDepth;
layout(set = 0, binding = RB_CHANGE_BINDING_REACTIVE) uniform sampler2D gReactive;
layout(set = 0, binding = RB_CHANGE_BINDING_SHADOWS, r8) uniform writeonly image2D shadowMask;
layout(set = 0, binding = RB_CHANGE_BINDING_AO, r8) uniform writeonly image2D aoMask;
layout(set = 0, binding = RB_CHANGE_BINDING_LOCAL_LIGHTS, r8) uniform writeonly image2D localLightMask;
layout(set = 0, binding = RB_CHANGE_BINDING_REFLECTIONS, r8) uniform writeonly image2D reflectionMask;

// Mirrors rb::ChangeBox (change_tracker.h): 32 bytes.
struct ChangeBox {
  vec3 lo;
  uint effects;  // RB_CHANGE_* bits
  vec3 hi;
  float pad;
};
layout(buffer_reference, std430, buffer_reference_align = 16) readonly buffer ChangeBoxes { ChangeBox b[]; };

// Squared distance from p to the box (0 inside).
float distance2(vec3 p, vec3 lo, vec3 hi) {
  vec3 d = max(max(lo - p, p - hi), vec3(0.0));
  return dot(d, d);
}

// Whether the segment p + t d, t in [0, tMax], meets the box (slab test). A zero component of d (the default sun,
// straight up) becomes a tiny one: an infinite inverse times a zero distance would be NaN, and min/max of NaN is not
// defined.
bool segmentHits(vec3 p, vec3 d, float tMax, vec3 lo, vec3 hi) {
  vec3 inv = 1.0 / mix(d, vec3(1e-20), lessThan(abs(d), vec3(1e-20)));
  vec3 t0 = (lo - p) * inv, t1 = (hi - p) * inv;
  vec3 tn = min(t0, t1), tf = max(t0, t1);
  float enter = max(max(tn.x, tn.y), max(tn.z, 0.0));
  float leave = min(min(tf.x, tf.y), min(tf.z, tMax));
  return enter <= leave;
}

void main() {
  uvec2 pixel = gl_GlobalInvocationID.xy;
  if (any(greaterThanEqual(pixel, pc.gbuffer.size))) return;
  ivec2 ip = ivec2(pixel);
  uint changed = 0u;
  if (pc.reactive != 0u && texelFetch(gReactive, ip, 0).r > 0.5) changed = pc.masks;
  float depth = texelFetch(gDepth, ip, 0).r;
  const bool reversedZ = (pc.gbuffer.flags & RB_GB_REVERSED_Z) != 0u;
  const bool sky = reversedZ ? depth <= 0.0 : depth >= 1.0;
  if (!sky && changed != pc.masks) {
    vec3 rel = rbReconstructCameraRelative(pixel, vec2(pc.gbuffer.size), depth, pc.gbuffer.inverseProjection,
                                           pc.gbuffer.viewToWorld, pc.gbuffer.wAtDepthOne, reversedZ);
    vec3 p = rel + pc.gbuffer.cameraToTlas;
    // The reconstructed point's error: a surface of the box's own object reads as inside.
    float margin = 1e-3 * length(rel) + 1e-4;
    vec3 toLight = pc.lightType == RB_LIGHT_DIRECTIONAL ? pc.lightDirection : pc.lightPosition - p;
    float lightDistance = pc.lightType == RB_LIGHT_DIRECTIONAL ? 1e30 : length(toLight);
    toLight = normalize(toLight);
    ChangeBoxes boxes = ChangeBoxes(pc.boxes);
    for (uint i = 0u; i < pc.boxCount && changed != pc.masks; ++i) {
      ChangeBox b = boxes.b[i];
      uint effects = b.effects & pc.masks & ~changed;
      if (effects == 0u) continue;
      float d2 = distance2(p, b.lo, b.hi);
      if (d2 <= margin * margin) {
        changed |= effects;
        continue;
      }
      if ((effects & RB_CHANGE_AO) != 0u && d2 <= (pc.aoRange + margin) * (pc.aoRange + margin))
        changed |= RB_CHANGE_AO;
      if ((effects & RB_CHANGE_SHADOWS) != 0u) {
        // Soft shadow rays spread: a directional light's by tan(angle) per unit of distance (taken at the box's
        // far side), a sphere light's by up to its radius.
        vec3 centre = 0.5 * (b.lo + b.hi);
        float reach = length(centre - p) + length(b.hi - centre);
        float widen = margin + (pc.lightType == RB_LIGHT_DIRECTIONAL ? pc.lightSpread * reach : pc.lightSpread);
        if (segmentHits(p, toLight, lightDistance, b.lo - widen, b.hi + widen)) changed |= RB_CHANGE_SHADOWS;
      }
    }
  }
  if ((pc.masks & RB_CHANGE_SHADOWS) != 0u)
    imageStore(shadowMask, ip, vec4((changed & RB_CHANGE_SHADOWS) != 0u ? 1.0 : 0.0));
  if ((pc.masks & RB_CHANGE_AO) != 0u) imageStore(aoMask, ip, vec4((changed & RB_CHANGE_AO) != 0u ? 1.0 : 0.0));
  if ((pc.masks & RB_CHANGE_LOCAL_LIGHTS) != 0u)
    imageStore(localLightMask, ip, vec4((changed & RB_CHANGE_LOCAL_LIGHTS) != 0u ? 1.0 : 0.0));
  if ((pc.masks & RB_CHANGE_REFLECTIONS) != 0u)
    imageStore(reflectionMask, ip, vec4((changed & RB_CHANGE_REFLECTIONS) != 0u ? 1.0 : 0.0));
}
