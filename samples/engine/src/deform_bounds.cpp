#include "deform_bounds.h"

#include <algorithm>
#include <cmath>

namespace sample_engine::detail {

DeformBoundsSource makeDeformBoundsSource(const MeshData& mesh, bool skinned) {
  DeformBoundsSource s;
  s.lo = glm::vec3(INFINITY);
  s.hi = glm::vec3(-INFINITY);
  for (const glm::vec3& p : mesh.positions) s.lo = glm::min(s.lo, p), s.hi = glm::max(s.hi, p);
  for (const MorphTarget& t : mesh.morphTargets) {
    glm::vec3 reach(0.0f);
    for (const glm::vec3& d : t.positionDeltas) reach = glm::max(reach, glm::abs(d));
    s.morphReach.push_back(reach);
  }
  if (!skinned || mesh.joints0.empty()) return s;
  auto add = [&](uint32_t joint, const glm::vec3& p) {
    if (joint >= s.jointLo.size()) {
      s.jointLo.resize(joint + 1, glm::vec3(INFINITY));
      s.jointHi.resize(joint + 1, glm::vec3(-INFINITY));
    }
    s.jointLo[joint] = glm::min(s.jointLo[joint], p);
    s.jointHi[joint] = glm::max(s.jointHi[joint], p);
  };
  for (size_t v = 0; v < mesh.positions.size(); ++v) {
    for (int k = 0; k < 4; ++k) {
      if (mesh.weights0[v][k] != 0.0f) add(mesh.joints0[v][k], mesh.positions[v]);
      if (!mesh.joints1.empty() && mesh.weights1[v][k] != 0.0f) add(mesh.joints1[v][k], mesh.positions[v]);
    }
  }
  return s;
}

void poseBounds(const DeformBoundsSource& source, std::span<const glm::mat4> joints, std::span<const float> weights,
                glm::vec3& lo, glm::vec3& hi) {
  // Morphing moves each vertex by at most the weighted reach of the targets, before skinning.
  glm::vec3 morph(0.0f);
  for (size_t t = 0; t < source.morphReach.size() && t < weights.size(); ++t)
    morph += std::abs(weights[t]) * source.morphReach[t];
  if (joints.empty() || source.jointLo.empty()) {
    lo = source.lo - morph;
    hi = source.hi + morph;
    return;
  }
  lo = glm::vec3(INFINITY);
  hi = glm::vec3(-INFINITY);
  for (size_t j = 0; j < source.jointLo.size() && j < joints.size(); ++j) {
    if (source.jointLo[j].x > source.jointHi[j].x) continue;  // influences no vertex
    const glm::vec3 a = source.jointLo[j] - morph, b = source.jointHi[j] + morph;
    const glm::mat4& m = joints[j];
    // The transformed box's box (Arvo): per axis, the translation plus each column's smaller and larger end.
    for (int r = 0; r < 3; ++r) {
      float l = m[3][r], h = m[3][r];
      for (int c = 0; c < 3; ++c) {
        const float x = m[c][r] * a[c], y = m[c][r] * b[c];
        l += std::min(x, y);
        h += std::max(x, y);
      }
      lo[r] = std::min(lo[r], l);
      hi[r] = std::max(hi[r], h);
    }
  }
  // Weights that do not sum to exactly one (rounded, or unnormalised by the asset) scale the mean slightly: a margin
  // of 1% of the box keeps such vertices inside.
  const glm::vec3 pad = 0.01f * (hi - lo) + 1e-6f;
  lo -= pad;
  hi += pad;
}

}  // namespace sample_engine::detail
