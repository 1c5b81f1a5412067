// The animated benchmark's scene: the procedural demo scene with K skinned characters (CesiumMan, Fox and
// BrainStem in turn, read from the shared glTF models, each scaled to 1.7 m along its largest extent) standing on
// its floor, each a copy of its own (own nodes, skin and animation, so its own deformed buffers and its own
// dynamic BLAS), each playing its first animation at its own time offset.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "sample_engine/engine.h"
#include "sample_engine/result.h"
#include "sample_engine/scene.h"

namespace rbAnimated {

struct AnimatedScene {
  sample_engine::Scene scene;
  std::vector<sample_engine::AnimationPlayback> playbacks;  // one per character
  std::vector<std::string> characterNames;                  // one per character, e.g. "CesiumMan"
  uint64_t characterTriangles = 0;                          // triangles of all characters together
};

// The models this benchmark animates, in the order characters cycle through them.
const std::vector<std::string>& characterModels();
// The characters stand on a square grid centred on the demo scene's centre (the benchmark), or on `gridCentreXZ`
// when given (raybridge-render --characters puts them in front of the demo's objects, in view of its camera).
// Fails (naming the folder and the missing files) when none of characterModels() is in `scenesDir`; the caller adds
// which of its options names the folder.
sample_engine::Result<AnimatedScene> makeAnimatedScene(const std::string& scenesDir, uint32_t characters,
                                                       std::optional<glm::vec2> gridCentreXZ = std::nullopt);

}  // namespace rbAnimated
