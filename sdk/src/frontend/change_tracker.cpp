#include "change_tracker.h"

#include <algorithm>
#include <cmath>
#include <cstring>

namespace rb {

namespace {

bool sameBounds(const MeshBounds& a, const MeshBounds& b) {
  return std::memcmp(a.min, b.min, sizeof a.min) == 0 && std::memcmp(a.max, b.max, sizeof a.max) == 0;
}

bool sameLight(const LightSource& a, const LightSource& b) {
  const Light& p = a.light;
  const Light& q = b.light;
  return p.type == q.type && std::memcmp(p.direction, q.direction, sizeof p.direction) == 0 &&
         std::memcmp(p.position, q.position, sizeof p.position) == 0 &&
         p.angularRadiusDegrees == q.angularRadiusDegrees && p.radius == q.radius && p.range == q.range &&
         p.spotOuterAngleDegrees == q.spotOuterAngleDegrees && std::memcmp(a.color, b.color, sizeof a.color) == 0 &&
         a.intensity == b.intensity && a.spotInnerAngleDegrees == b.spotInnerAngleDegrees;
}

}  // namespace

void ChangeTracker::addInstanceBox(const float t[12], const MeshBounds& bounds, bool reveals) {
  if (!bounds.given()) return;
  // The box of the transformed box (Arvo): per world axis, the translation plus each object axis's contribution at
  // whichever end of the box makes it smallest and largest.
  WorldChangeBox box;
  box.effects = kChangeAllEffects | (reveals ? RB_CHANGE_REVEALS : 0u);
  for (int r = 0; r < 3; ++r) {
    double lo = t[r * 4 + 3], hi = t[r * 4 + 3];
    for (int c = 0; c < 3; ++c) {
      const double a = double(t[r * 4 + c]) * bounds.min[c], b = double(t[r * 4 + c]) * bounds.max[c];
      lo += std::min(a, b);
      hi += std::max(a, b);
    }
    // A non-finite transform has no box to reset; the TLAS build skips nothing for it, but neither can we bound it.
    if (!std::isfinite(lo) || !std::isfinite(hi)) return;
    box.lo[r] = lo;
    box.hi[r] = hi;
  }
  boxes_.push_back(box);
}

void ChangeTracker::addLightBox(const LightSource& source) {
  const Light& l = source.light;
  WorldChangeBox box;
  box.effects = RB_CHANGE_LOCAL_LIGHTS;
  const bool bounded = l.type != LightType::Directional && l.range > 0.0f && std::isfinite(l.range);
  for (int i = 0; i < 3; ++i) {
    const double reach = bounded ? double(l.range) + l.radius : kUnboundedChange;
    const double centre = bounded ? l.position[i] : 0.0;
    box.lo[i] = centre - reach;
    box.hi[i] = centre + reach;
  }
  boxes_.push_back(box);
}

void ChangeTracker::update(std::span<const Instance> instances,
                           std::span<const AccelerationStructureService::MeshChange> meshes,
                           std::span<const LightSource> lights, std::span<const ChangedBox> engine) {
  // The last frames' boxes, newest first: the follow-up boxes of toGpu().
  if (primed_) {
    recent_.insert(recent_.begin(), std::move(boxes_));
    if (recent_.size() > kMaxResetFollowUpFrames) recent_.pop_back();
  }
  boxes_.clear();
  if (primed_) {
    const size_t common = std::min(instances.size(), instances_.size());
    for (size_t i = 0; i < instances.size(); ++i) {
      const Instance& now = instances[i];
      const AccelerationStructureService::MeshChange& change = meshes[i];
      if (i < common) {
        const SeenInstance& was = instances_[i];
        // A new pose that brings its own box changed where that box changed; one without is a change as such.
        const bool deformed = was.change.poses != change.poses && !change.poseBounds;
        if (was.mesh == now.mesh && std::memcmp(was.transform, now.transform, sizeof was.transform) == 0 && !deformed &&
            sameBounds(was.change.bounds, change.bounds)) {
          continue;
        }
        addInstanceBox(was.transform, was.change.bounds, /*reveals=*/true);
      }
      addInstanceBox(now.transform, change.bounds, /*reveals=*/false);  // moved, deformed or appeared: where it is now
    }
    for (size_t i = common; i < instances_.size(); ++i)  // vanished: where it was
      addInstanceBox(instances_[i].transform, instances_[i].change.bounds, /*reveals=*/true);
    const size_t commonLights = std::min(lights.size(), lights_.size());
    for (size_t i = 0; i < lights.size(); ++i) {
      if (i < commonLights && sameLight(lights[i], lights_[i])) continue;
      if (i < commonLights) addLightBox(lights_[i]);
      addLightBox(lights[i]);
    }
    for (size_t i = commonLights; i < lights_.size(); ++i) addLightBox(lights_[i]);
  }
  for (const ChangedBox& e : engine) {
    WorldChangeBox box;
    box.effects = kChangeAllEffects | RB_CHANGE_REVEALS;  // the engine's box may be where something was
    for (int i = 0; i < 3; ++i) box.lo[i] = e.min[i], box.hi[i] = e.max[i];
    boxes_.push_back(box);
  }
  instances_.resize(instances.size());
  for (size_t i = 0; i < instances.size(); ++i) {
    instances_[i].mesh = instances[i].mesh;
    std::memcpy(instances_[i].transform, instances[i].transform, sizeof instances_[i].transform);
    instances_[i].change = meshes[i];
  }
  lights_.assign(lights.begin(), lights.end());
  primed_ = true;
}

namespace {

GpuChangeBox toGpuBox(const WorldChangeBox& w, const double originOffset[3], uint32_t effects) {
  GpuChangeBox g{};
  for (int i = 0; i < 3; ++i) {
    // Rounded outwards so the float box holds the double one.
    g.lo[i] = std::nextafter(float(w.lo[i] - originOffset[i]), -INFINITY);
    g.hi[i] = std::nextafter(float(w.hi[i] - originOffset[i]), INFINITY);
  }
  g.effects = effects;
  return g;
}

void mergeInto(GpuChangeBox& last, const GpuChangeBox& g) {
  for (int i = 0; i < 3; ++i) last.lo[i] = std::min(last.lo[i], g.lo[i]), last.hi[i] = std::max(last.hi[i], g.hi[i]);
  last.effects |= g.effects;
}

}  // namespace

void ChangeTracker::toGpu(const double originOffset[3], const ChangeFollowUp& followUp,
                          std::vector<GpuChangeBox>& out) const {
  out.clear();
  // Revealed pixels are marked at the follow-up level: without follow-ups, none.
  const uint32_t keep = followUp.frames > 0 && followUp.effects != 0u ? ~0u : ~RB_CHANGE_REVEALS;
  for (const WorldChangeBox& w : boxes_) {
    const GpuChangeBox g = toGpuBox(w, originOffset, w.effects & keep);
    if (out.size() < kMaxChangeBoxes) out.push_back(g);
    else
      mergeInto(out.back(), g);
  }
  // The follow-ups take the room this frame's boxes leave. Past it they merge into the last follow-up box, never
  // into one of this frame's (which would restart its pixels); with no room at all they are dropped: fewer extra
  // rays, no missed restart.
  const size_t frames = std::min<size_t>(followUp.frames, recent_.size());
  for (size_t f = 0; f < frames; ++f) {
    for (const WorldChangeBox& w : recent_[f]) {
      const uint32_t effects = w.effects & followUp.effects;
      if (effects == 0u) continue;
      const GpuChangeBox g = toGpuBox(w, originOffset, effects | (w.effects & RB_CHANGE_REVEALS) | RB_CHANGE_FOLLOW_UP);
      if (out.size() < kMaxChangeBoxes) out.push_back(g);
      else if (out.back().effects & RB_CHANGE_FOLLOW_UP)
        mergeInto(out.back(), g);
    }
  }
}

void ChangeTracker::forget() {
  instances_.clear();
  lights_.clear();
  recent_.clear();
  boxes_.clear();
  primed_ = false;
}

}  // namespace rb
