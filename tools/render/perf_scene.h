// The performance scene of docs/performance.md: the shared glTF models (static ones only), each loaded once and
// instanced many times on a finely tessellated ground, so that the effect passes trace a million-plus triangles
// of real geometry in a hundred-plus instances. Built from ../shared/scenes at run time; nothing is copied in.
#pragma once

#include <cstdint>
#include <string>

#include "sample_engine/result.h"
#include "sample_engine/scene.h"

namespace rbRender {

// Ground: a square of kPerfGroundSize metres in kPerfGroundSegments^2 quads (2 triangles each): 1,179,648
// triangles, fine enough that shadow and AO rays land on real tessellation rather than on two huge triangles.
inline constexpr float kPerfGroundSize = 80.0f;
inline constexpr uint32_t kPerfGroundSegments = 768;

// What the scene holds: the cost curves of docs/performance.md vary these (ground only for the triangle curve, more
// copies for the instance curve). A zero-initialised PerfSceneShape is the default scene.
struct PerfSceneShape {
  uint32_t groundSegments = 0;  // 0 = kPerfGroundSegments; quads per side of the ground
  // Copies of every model relative to the default scene; 0 = 1. With groundOnly, no model at all.
  uint32_t copiesScale = 0;
  bool groundOnly = false;
};

struct PerfSceneInfo {
  uint64_t triangles = 0;  // summed over instances (what the TLAS holds)
  uint64_t instances = 0;  // Scene::instances
  uint32_t models = 0;     // distinct glTF models found and placed
  std::string missing;     // the models that were not found (comma-separated), for a warning
};

// The models placed, from the largest: ReciprocatingSaw, 2CylinderEngine, DamagedHelmet, Suzanne, Duck and
// MetalRoughSpheresNoTextures, each on a ring of plinths around the centre. Fails, naming the folder and the files
// looked for, when none is in `scenesDir`; a missing model is skipped and listed in PerfSceneInfo::missing.
// Deterministic: the same folder gives the same scene. Has a camera (looking over the rings) and a low sun.
sample_engine::Result<sample_engine::Scene> makePerfScene(const std::string& scenesDir, PerfSceneInfo& info,
                                                          const PerfSceneShape& shape = {});

}  // namespace rbRender
