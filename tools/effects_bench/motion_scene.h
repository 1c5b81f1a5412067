// The motion benchmark's scene (raybridge-effects-bench --scenario motion): the demo scene, optionally with walking
// skinned characters (the animated benchmark's, when the shared glTF models are there), plus three props whose motion
// the cases single out, each driven by an animation of its own so that a case plays only its own:
//   * a pillar that teleports (STEP translation) across open ground in front of the mirror patch: its shadow, its
//     AO contact and its reflection jump;
//   * a door that swings on a vertical hinge (LINEAR rotation, steady motion);
//   * a point lamp that jumps (STEP translation of the light's node): the local-light irradiance moves at once.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "sample_engine/scene.h"

namespace rbEffects {

struct MotionScene {
  sample_engine::Scene scene;
  uint32_t teleportAnimation = 0, doorAnimation = 0, lampAnimation = 0;
  std::vector<sample_engine::AnimationPlayback> walkers;  // empty when the characters are not there
  std::string walkersNote;                                // why not, or which characters walk
};

// Seconds into an event animation at which the pillar and the lamp jump.
inline constexpr double kMotionEventTime = 1.0;

// `scenesDir`: where CesiumMan, Fox and BrainStem are (the walkers case); empty or missing = no walkers.
MotionScene makeMotionScene(const std::string& scenesDir, uint32_t characters);

}  // namespace rbEffects
