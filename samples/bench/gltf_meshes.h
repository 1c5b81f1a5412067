// glTF models flattened for the benchmark: each glTF mesh becomes one CPU mesh (its triangle primitives with
// POSITION and indices merged), each node that references a mesh one instance with its world transform.
// Nothing is copied into the repository: models are read from --scenes (default ../shared/scenes).
#pragma once

#include <string>
#include <vector>

#include "procedural_meshes.h"
#include "scene_meshes.h"

namespace rbbench {

struct GltfModel {
  std::string name;
  std::vector<rbsamples::CpuMesh> meshes;  // non-empty meshes only
  struct Placement {
    uint32_t mesh;
    Transform transform;
  };
  std::vector<Placement> instances;
  uint64_t uniqueTriangles() const;
};

// Primitives: triangle lists with float POSITION, indexed (8/16/32-bit) or not; others are left out.
// Loads every model folder under `dir` (the first .gltf or .glb file in each), sorted by name. Models that fail
// to load or hold no triangles are reported in `messages` and skipped. Returns an empty list (with a message)
// when `dir` does not exist or glTF support was not compiled in.
std::vector<GltfModel> loadGltfModels(const std::string& dir, std::vector<std::string>& messages);

}  // namespace rbbench
