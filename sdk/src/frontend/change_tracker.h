// Where HybridEffects knows the world changed since its last frame: the world-space boxes of instances that moved,
// appeared, vanished or deformed, of local lights that changed, and the engine's own (HybridFrame::changedBoxes).
// change_masks.h turns them into per-effect masks of the pixels whose history is reset.
//
// Instances and lights are matched by their index in the frame's list: the engine's lists keep their order from
// frame to frame (a reordered list reads as every reordered entry changed: more resets, never a missed one). An
// instance changed when its mesh, transform or mesh box changed (AccelerationStructureService::meshChanges), or when
// its dynamic mesh was updated without a pose box of its own (MeshUpdate::bounds); its box is the mesh's box under
// the transform, before and after. An update that brings an unchanged pose box is read as the same pose: engines
// update paused characters every frame. A mesh without a known box contributes none: anti-lag alone follows it.
//
// Thread safety: none; owned by one HybridEffects, used by its record().
#pragma once

#include <raybridge/acceleration_structures.h>
#include <raybridge/hybrid_effects.h>
#include <raybridge/light_list.h>

#include <cstdint>
#include <span>
#include <vector>

#include "raybridge_shader_interface.glsl"

namespace rb {

// The effects every instance and engine box concerns (RB_CHANGE_* bits).
inline constexpr uint32_t kChangeAllEffects = RB_CHANGE_SHADOWS | RB_CHANGE_AO | RB_CHANGE_LOCAL_LIGHTS |
                                              RB_CHANGE_REFLECTIONS;
// Boxes a frame sends to the GPU at most; the rest are merged into the last one (a larger box: more resets, none
// missed). Each costs every pixel a box test.
inline constexpr uint32_t kMaxChangeBoxes = RB_CHANGE_MAX_BOXES;
// The half-extent given to a change without a bound (a local light of unlimited range, or a directional one).
inline constexpr double kUnboundedChange = 1e30;

struct WorldChangeBox {
  double lo[3] = {0.0, 0.0, 0.0};
  double hi[3] = {0.0, 0.0, 0.0};
  uint32_t effects = 0;  // RB_CHANGE_* bits
};

// Mirrors ChangeBox in shaders/change_masks.comp (std430): TLAS space.
struct GpuChangeBox {
  float lo[3];
  uint32_t effects;
  float hi[3];
  float pad;
};
static_assert(sizeof(GpuChangeBox) == 32);

// Which of the last frames' boxes toGpu() sends again as follow-up boxes (RB_CHANGE_FOLLOW_UP): the boxes of the
// `frames` frames before this one, for `effects` (RB_CHANGE_* bits: the effects that trace reset rays).
struct ChangeFollowUp {
  uint32_t frames = 0;  // at most kMaxResetFollowUpFrames
  uint32_t effects = 0;
};

class ChangeTracker {
 public:
  // This frame's changes against the previous call's lists (none on the first call, or after forget()).
  // `meshes[i]` is instances[i]'s (AccelerationStructureService::meshChanges); `engine`: HybridFrame::changedBoxes.
  void update(std::span<const Instance> instances, std::span<const AccelerationStructureService::MeshChange> meshes,
              std::span<const LightSource> lights, std::span<const ChangedBox> engine);
  const std::vector<WorldChangeBox>& boxes() const { return boxes_; }
  // This frame's boxes in the space of a TLAS built at `originOffset`, then those of `followUp`, at most
  // kMaxChangeBoxes in all (this frame's come first). Without follow-ups (no frames or no effects) no box carries
  // RB_CHANGE_REVEALS: revealed pixels are follow-up marks.
  void toGpu(const double originOffset[3], const ChangeFollowUp& followUp, std::vector<GpuChangeBox>& out) const;
  // The next update() compares against nothing and has no follow-ups (after a history reset: nothing to keep).
  void forget();

 private:
  struct SeenInstance {
    MeshHandle mesh;
    float transform[12];
    AccelerationStructureService::MeshChange change;
  };
  // `reveals`: the box is where the instance was (RB_CHANGE_REVEALS: what it hid may be visible now).
  void addInstanceBox(const float transform[12], const MeshBounds& bounds, bool reveals);
  void addLightBox(const LightSource& light);

  std::vector<SeenInstance> instances_;
  std::vector<LightSource> lights_;
  bool primed_ = false;
  std::vector<WorldChangeBox> boxes_;
  std::vector<std::vector<WorldChangeBox>> recent_;  // the last frames' boxes_, newest first
};

}  // namespace rb
