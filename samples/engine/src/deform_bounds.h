// The box of a deforming instance's current pose, on the CPU, without reading the GPU's deformed vertices: what a
// culling pass tests, and what DeformedInstance::boundsMin/Max report. Linear-blend skinning puts a vertex at a
// weighted mean of its joints' transforms of it, so it lies in the box around those joints' transformed bind-space
// boxes: per joint, the box of the vertices it influences (widened by the morph targets' reach at this frame's
// weights), under this frame's joint matrix, and the union of them all.
#pragma once

#include <glm/glm.hpp>

#include <span>
#include <vector>

#include "sample_engine/scene.h"

namespace sample_engine::detail {

struct DeformBoundsSource {
  // Skinned: per joint of the skin, the bind-space box of the vertices it influences (lo > hi: none).
  std::vector<glm::vec3> jointLo, jointHi;
  glm::vec3 lo{0.0f}, hi{0.0f};       // every vertex, bind space (unskinned meshes)
  std::vector<glm::vec3> morphReach;  // per morph target: the largest |position delta| per axis
};

DeformBoundsSource makeDeformBoundsSource(const MeshData& mesh, bool skinned);

// The local-space box of the pose given by `joints` (the instance's skinning matrices; empty = not skinned) and
// `weights` (its morph weights).
void poseBounds(const DeformBoundsSource& source, std::span<const glm::mat4> joints, std::span<const float> weights,
                glm::vec3& lo, glm::vec3& hi);

}  // namespace sample_engine::detail
