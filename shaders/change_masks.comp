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
//   - follow-up level (below) for the box's effects: where the segment from P to the camera crosses a box of where
//     geometry was (RB_CHANGE_REVEALS): P may be newly visible, without a history to reproject (the motion bench's
//     teleport: half the changed pixels of the shadows were such, starting from one frame of the usual rays).
// Local-light boxes (RB_CHANGE_LOCAL_LIGHTS only) are a light's range: where it can light, it lit differently.
// The engine's reactive mask is set in every mask. Each mask is 1 (changed) or 0, or RB_REACTIVE_FOLLOW_UP_VALUE
// where only a follow-up box (RB_CHANGE_FOLLOW_UP: a change of one of the last frames) changes the pixel: there the
// effect's pass traces its reset rays again and its denoiser keeps the history they restarted.
#include "raybridge_gbuffer.glsl"
#include "raybridge_pass_constants.glsl"
#include "segment_box.glsl"

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


// Per 8x8 workgroup, the boxes that can change any of its pixels: each box is tested once against the tile's surface
// points (their bounding box, by the Minkowski sum with it), so a pixel loops over the few boxes near it instead of
// every box of the frame. Every per-pixel test below is implied by the tile's (a superset), so the masks are the same.
shared vec3 tileLo[64];
shared vec3 tileHi[64];
shared uint candidateCount;
shared uint candidates[RB_CHANGE_MAX_BOXES];

// Which of `effects` box b changes at the surface points within `extent` of `c` (per axis), `margin` being the
// largest of their reconstruction margins: a pixel's own test is extent 0, a tile's is its points' bounding box (the
// box grown by it: a test from c then stands for every point, so the tile's result holds every pixel's). `revealed`:
// the effects for which those points may be newly visible through the box (RB_CHANGE_REVEALS; follow-up level). The
// segments from the tile's points to the camera lie within `extent` of the one from c, as a point light's do.
uint changedEffects(ChangeBox b, uint effects, vec3 c, vec3 extent, float margin, out uint revealed) {
  vec3 lo = b.lo - extent, hi = b.hi + extent;
  float d2 = distance2(c, lo, hi);
  revealed = 0u;
  if (d2 <= margin * margin) return effects;  // on the object itself
  if ((b.effects & RB_CHANGE_REVEALS) != 0u) {
    vec3 toCamera = pc.gbuffer.cameraToTlas - c;
    float cameraDistance = length(toCamera);
    if (cameraDistance > 0.0 && rbSegmentHitsBox(c, toCamera / cameraDistance, cameraDistance, lo - margin, hi + margin))
      revealed = effects;
  }
  uint changed = 0u;
  if ((effects & RB_CHANGE_AO) != 0u && d2 <= (pc.aoRange + margin) * (pc.aoRange + margin)) changed |= RB_CHANGE_AO;
  if ((effects & RB_CHANGE_SHADOWS) != 0u) {
    // Soft shadow rays spread: a directional light's by tan(angle) per unit of distance (taken at the box's far
    // side), a sphere light's by up to its radius.
    vec3 centre = 0.5 * (b.lo + b.hi);
    float reach = length(centre - c) + length(extent) + length(b.hi - centre);
    float widen = margin + (pc.lightType == RB_LIGHT_DIRECTIONAL ? pc.lightSpread * reach : pc.lightSpread);
    vec3 toLight = pc.lightType == RB_LIGHT_DIRECTIONAL ? pc.lightDirection : pc.lightPosition - c;
    float lightDistance = pc.lightType == RB_LIGHT_DIRECTIONAL ? 1e30 : length(toLight);
    // A point light's segments from the tile's points lie within `extent` of the one from c (their hull); a
    // directional light's rays are parallel.
    if (rbSegmentHitsBox(c, normalize(toLight), lightDistance, lo - widen, hi + widen)) changed |= RB_CHANGE_SHADOWS;
  }
  return changed;
}

void main() {
  uvec2 pixel = gl_GlobalInvocationID.xy;
  const uint local = gl_LocalInvocationIndex;
  // Threads outside the image take part in the workgroup's steps (barriers) but write nothing.
  const bool inImage = all(lessThan(pixel, pc.gbuffer.size));
  ivec2 ip = ivec2(min(pixel, pc.gbuffer.size - 1u));
  uint changed = 0u;
  if (pc.reactive != 0u && texelFetch(gReactive, ip, 0).r > 0.5) changed = pc.masks;
  float depth = texelFetch(gDepth, ip, 0).r;
  const bool reversedZ = (pc.gbuffer.flags & RB_GB_REVERSED_Z) != 0u;
  const bool sky = reversedZ ? depth <= 0.0 : depth >= 1.0;
  const bool test = inImage && !sky && changed != pc.masks;
  vec3 rel = vec3(0.0), p = vec3(0.0);
  if (test) {
    rel = rbReconstructCameraRelative(pixel, vec2(pc.gbuffer.size), depth, pc.gbuffer.inverseProjection,
                                      pc.gbuffer.viewToWorld, pc.gbuffer.wAtDepthOne, reversedZ);
    p = rel + pc.gbuffer.cameraToTlas;
  }
  tileLo[local] = test ? p : vec3(1e30);
  tileHi[local] = test ? p : vec3(-1e30);
  if (local == 0u) candidateCount = 0u;
  barrier();
  for (uint stride = 32u; stride > 0u; stride >>= 1) {
    if (local < stride) {
      tileLo[local] = min(tileLo[local], tileLo[local + stride]);
      tileHi[local] = max(tileHi[local], tileHi[local + stride]);
    }
    barrier();
  }
  const vec3 tLo = tileLo[0], tHi = tileHi[0];
  if (tLo.x <= tHi.x) {
    const vec3 c = 0.5 * (tLo + tHi), extent = 0.5 * (tHi - tLo);
    const float tileMargin = 1e-3 * (length(c - pc.gbuffer.cameraToTlas) + length(extent)) + 1e-4;
    ChangeBoxes boxes = ChangeBoxes(pc.boxes);
    for (uint i = local; i < pc.boxCount; i += 64u) {
      uint revealed;
      if ((changedEffects(boxes.b[i], boxes.b[i].effects & pc.masks, c, extent, tileMargin, revealed) | revealed) != 0u)
        candidates[atomicAdd(candidateCount, 1u)] = i;
    }
  }
  barrier();

  uint followUp = 0u;  // effects only a follow-up box changes here
  if (test) {
    // The reconstructed point's error: a surface of the box's own object reads as inside.
    float margin = 1e-3 * length(rel) + 1e-4;
    ChangeBoxes boxes = ChangeBoxes(pc.boxes);
    for (uint k = 0u; k < candidateCount && changed != pc.masks; ++k) {
      ChangeBox b = boxes.b[candidates[k]];
      const bool isFollowUp = (b.effects & RB_CHANGE_FOLLOW_UP) != 0u;
      uint effects = b.effects & pc.masks & ~changed & (isFollowUp ? ~followUp : ~0u);
      if (effects == 0u) continue;
      uint revealed;
      const uint hit = changedEffects(b, effects, p, vec3(0.0), margin, revealed);
      if (isFollowUp) followUp |= hit;
      else changed |= hit;
      followUp |= revealed;
    }
  }
  if (!inImage) return;
  // The stronger mark wins: a pixel this frame's change restarts is not a follow-up.
  const vec4 value[3] = vec4[3](vec4(0.0), vec4(RB_REACTIVE_FOLLOW_UP_VALUE), vec4(1.0));
  #define RB_MARK(effect) value[(changed & effect) != 0u ? 2 : (followUp & effect) != 0u ? 1 : 0]
  if ((pc.masks & RB_CHANGE_SHADOWS) != 0u) imageStore(shadowMask, ip, RB_MARK(RB_CHANGE_SHADOWS));
  if ((pc.masks & RB_CHANGE_AO) != 0u) imageStore(aoMask, ip, RB_MARK(RB_CHANGE_AO));
  if ((pc.masks & RB_CHANGE_LOCAL_LIGHTS) != 0u) imageStore(localLightMask, ip, RB_MARK(RB_CHANGE_LOCAL_LIGHTS));
  if ((pc.masks & RB_CHANGE_REFLECTIONS) != 0u) imageStore(reflectionMask, ip, RB_MARK(RB_CHANGE_REFLECTIONS));
}
