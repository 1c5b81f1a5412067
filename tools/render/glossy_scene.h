// The glossy scene of docs/performance.md (issue 30): a tiled, polished floor under a grid of finely tessellated
// metal spheres, tori, boxes and columns, so that most pixels of every view reflect at roughness 0.2-0.5 and the
// reflection pass is measured where it dominates. Procedural and deterministic: it needs no file.
#pragma once

#include <cstdint>

#include "sample_engine/scene.h"

namespace rbRender {

// Floor: a square of kGlossyFloorSize metres in kGlossyFloorSegments^2 quads (204,800 triangles), wide enough that
// every camera of scripts/gpu/glossy_path.json sees floor up to the top of the image (no sky), at 16:9 too.
inline constexpr float kGlossyFloorSize = 96.0f;
inline constexpr uint32_t kGlossyFloorSegments = 320;
// Objects: one per cell of a kGlossyGridCells^2 grid, kGlossyGridSpacing metres apart, centred on the origin.
inline constexpr uint32_t kGlossyGridCells = 9;
inline constexpr float kGlossyGridSpacing = 4.5f;
// The glossy roughness range every floor texel and every glossy material stays inside, clear of [0.2, 0.5]'s
// ends so that the pre-pass's 16-bit float roughness does not round out of it.
inline constexpr float kGlossyMinRoughness = 0.22f, kGlossyMaxRoughness = 0.48f;

// The scene: the floor (base colour and metallic-roughness textures of 1 m tiles, metal and polished stone, roughness
// 0.25-0.47) and 81 objects of four shapes (spheres of 25,280 triangles, tori of 20,480, boxes of 6,912, capped
// columns of 12,544) scaled 0.8-1.25 and turned at random. Each shape has four glossy materials (roughness 0.24-0.46,
// a generated checker texture tinting gold, copper, steel and so on) and one contrast material (mirror spheres and
// tori, rough boxes and columns, about one object in ten). Shape variants share their geometry, so the SDK builds one
// BLAS per shape (content-hash dedup) and instances it. About 1.6M triangles in 82 instances. Has a camera (the
// first keyframe of scripts/gpu/glossy_path.json) and a sun. Deterministic: every call gives the same scene.
sample_engine::Scene makeGlossyScene();

}  // namespace rbRender
