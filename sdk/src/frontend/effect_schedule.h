// How HybridEffects turns an effect's RaySchedule into the one its pass runs: the history is the effect's own
// denoiser, and the reset rays it asks for by default (kDefaultResetRaysFactor). Used by hybrid_effects.cpp alone.
//
// Thread safety: pure functions.
#pragma once

#include <raybridge/effects.h>
#include <raybridge/hybrid_effects.h>
#include <raybridge/ray_schedule.h>

#include <algorithm>
#include <cstdint>
#include <span>
#include <vector>

#include "change_tracker.h"

namespace rb {

// An effect's schedule as its pass runs it: its history is the effect's denoiser, and the stages that read it wait
// for the denoiser's first frame (none before it: uniform rays, nothing skipped). `allowed` false (a hard shadow)
// turns them off.
inline RaySchedule effectSchedule(const RaySchedule& wanted, const Denoiser* history, bool allowed = true) {
  RaySchedule s = wanted;
  s.history = history;
  s.adaptive.enabled = s.adaptive.enabled && history && allowed;
  s.convergedTiles.enabled = s.convergedTiles.enabled && history && allowed;
  return s;
}

// RaySchedule::resetRays as HybridEffects asks for it (kDefaultResetRaysFactor): only where a denoiser keeps a
// history for the extra rays to start (`history`), and where the schedule traces every pixel its own count.
inline uint32_t effectResetRays(const RaySchedule& s, bool disabled, uint32_t rays) {
  if (disabled || !s.history || s.adaptive.enabled || s.halfResolution) return 0u;
  return s.resetRays ? s.resetRays : std::min(kDefaultResetRaysFactor * rays, kMaxRaysPerPixel);
}

// DenoiseSettings::resetFrames for a pass that traced `resetRays` instead of `rays` in a restarted pixel: whole
// frames, rounded down (the frame weighs a little less than its rays, never more).
inline uint32_t denoiserResetFrames(uint32_t resetRays, uint32_t rays) {
  return resetRays > rays && rays > 0u ? resetRays / rays : 0u;
}

// The change tracker's boxes as HybridEffects hands them to the reflection rays (ReflectionSettings::relitBoxes): the
// reaches of the local lights that changed. Not the instance boxes: every reflection pixel whose ray meets a moved
// object's box restarts, and with three walking characters (122 pose boxes, restarted every frame) the reflections'
// error moving against at rest went from 1.25 to 1.92 and the pass from 1.46 to 1.65 ms (H100, 2560x1440,
// 2026-12-06), while anti-lag already follows a moved object in a mirror (the teleport's reflection: lag 0). A
// light's change is what anti-lag missed (the lamp jump's reflection: lag > 6). Past kMaxReflectionChangedBoxes the
// list becomes its union (a union restarts more pixels, never fewer).
inline void reflectionRelitBoxes(std::span<const WorldChangeBox> boxes, std::vector<ChangedBox>& relit) {
  relit.clear();
  for (const WorldChangeBox& w : boxes) {
    if ((w.effects & RB_CHANGE_REFLECTIONS) != 0u || (w.effects & RB_CHANGE_LOCAL_LIGHTS) == 0u) continue;
    ChangedBox b;
    for (int a = 0; a < 3; ++a) b.min[a] = w.lo[a], b.max[a] = w.hi[a];
    relit.push_back(b);
  }
  if (relit.size() <= kMaxReflectionChangedBoxes) return;
  ChangedBox u = relit.front();
  for (const ChangedBox& b : relit) {
    for (int a = 0; a < 3; ++a) u.min[a] = std::min(u.min[a], b.min[a]), u.max[a] = std::max(u.max[a], b.max[a]);
  }
  relit.assign(1, u);
}

}  // namespace rb
