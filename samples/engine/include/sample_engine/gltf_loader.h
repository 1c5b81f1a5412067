// glTF 2.0 (.gltf / .glb) loading into the engine's Scene.
#pragma once

#include <string>
#include <vector>

#include "sample_engine/scene.h"

namespace sample_engine {

struct SceneLoadResult {
  Scene scene;
  std::string error;                  // empty on success
  std::vector<std::string> warnings;  // e.g. skipped non-triangle primitives, unsupported features

  bool ok() const { return error.empty(); }
};

// Loads the default scene of the file (or scene 0, or every root node when none is declared): the node
// hierarchy is flattened into instances, each glTF primitive becomes one MeshData, the first perspective
// camera found in the hierarchy becomes Scene::camera. Never throws.
SceneLoadResult loadGltf(const std::string& path);

}  // namespace sample_engine
