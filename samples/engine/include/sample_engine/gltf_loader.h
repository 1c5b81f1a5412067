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
// hierarchy is flattened into instances (scene roots in order, depth-first pre-order, a node's primitives in
// order; Instance::node / skin name the glTF node and skin), each glTF primitive becomes one MeshData, the
// first perspective camera found in the hierarchy becomes Scene::camera. Animation data is kept: every glTF
// node (same indices, TRS or matrix, parent), skins (joints, inverse bind matrices), animations (translation,
// rotation, scale and weights channels; LINEAR, STEP, CUBICSPLINE; duration = the largest key time), per
// primitive JOINTS_0/WEIGHTS_0 (+ JOINTS_1/WEIGHTS_1) and morph targets (POSITION / NORMAL deltas, sparse
// accessors included) with the mesh's default weights. KHR_lights_punctual: one Scene::lights entry per node
// that places a light, in the order the hierarchy is visited (as instances), with PunctualLight::node = that
// node (so it follows the node's animation) and transform = its rest-pose world transform; the light's
// fields as the file gives them (absent range = 0 = unlimited; spot cones default to 0 and pi/4). A bad light
// (unknown type, negative colour or intensity, a given range <= 0, inner cone >= outer or outer > pi/2, a
// light index out of range, more than kMaxPunctualLights) fails naming the light index and the field. Bad input (an
// out-of-range node, mesh, skin or accessor index, a joint index beyond its skin's joint count, a skinned vertex whose
// weights sum to 0, ...) fails with an error naming the value. Never throws.
SceneLoadResult loadGltf(const std::string& path);

}  // namespace sample_engine
