// The numbers the generated fixtures (gltf_fixtures.h) are built from, shared with the tests so that their
// expectations are derived from the same definitions (and can be computed analytically) instead of repeated
// literals. Thread-safe: constants and pure functions.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>

#include <glm/glm.hpp>
#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/quaternion.hpp>

namespace pose_reference::fixture {

// ---- Skinned strip (writeSkinnedStrip) ----
// Node layout: 0 "root" (children 1, 2), 1 "strip" (the skinned mesh node), 2 "joint0" -> 3 "joint1" -> 4
// "joint2". Skin joints {2, 3, 4}. Instance order: one primitive, node 1.
inline constexpr int kStripRootNode = 0, kStripMeshNode = 1, kStripFirstJointNode = 2;
inline constexpr int kStripRows = 21;  // vertices per column, 2 columns: 42 vertices, 40 triangles
inline constexpr int kStripVertexCount = 2 * kStripRows;
inline constexpr double kStripRowSpacing = 0.15;  // 20 rows * 0.15 = 3 = three bones of length 1
inline constexpr double kStripHalfWidth = 0.25;
inline constexpr int kStripJointCount = 3;
inline constexpr double kStripBoneLength = 1.0;  // joint1 and joint2 sit at (0, 1, 0) in their parent
inline constexpr double kStripRootYawDegrees = 30.0;
inline constexpr double kStripRootScale = 1.5;  // uniform, so joint rotations stay rotations in world space
inline glm::dvec3 stripRootTranslation() { return {1.0, 0.5, -2.0}; }
inline glm::dquat stripRootRotation() {
  return glm::angleAxis(glm::radians(kStripRootYawDegrees), glm::dvec3(0, 1, 0));
}
inline glm::dmat4 stripRootMatrix() {
  return glm::translate(glm::dmat4(1.0), stripRootTranslation()) * glm::mat4_cast(stripRootRotation()) *
         glm::scale(glm::dmat4(1.0), glm::dvec3(kStripRootScale));
}
// The mesh node's own transform: ignored by skinning (glTF), but it defines the engine's local (deformed)
// space.
inline glm::dvec3 stripMeshNodeTranslation() { return {0.5, 0.25, 0.0}; }
inline glm::dquat stripMeshNodeRotation() { return glm::angleAxis(glm::radians(20.0), glm::dvec3(1, 0, 0)); }

inline int stripVertexIndex(int row, int column) { return row * 2 + column; }
// Vertex position in the strip's own frame (before the root transform): x = -/+ half width, y = row *
// spacing.
inline glm::dvec3 stripLocalVertex(int row, int column) {
  return {column == 0 ? -kStripHalfWidth : kStripHalfWidth, row * kStripRowSpacing, 0.0};
}
// The stored (bind) POSITION: the strip placed by the root, because the inverse bind matrices are the
// inverses of the joints' bind world transforms (root included). So at the bind pose every joint matrix is
// identity.
inline glm::dvec3 stripBindPosition(int row, int column) {
  return glm::dvec3(stripRootMatrix() * glm::dvec4(stripLocalVertex(row, column), 1.0));
}
// Total weight of each joint at height y: tents of half-width kStripTentHalfWidth centred on the bones,
// normalized to sum 1; in the middle of the strip all three joints contribute. The writer spreads each total
// over several of the 8 influence slots (see gltf_fixtures.cpp), so every slot of such a vertex has a
// non-zero weight.
inline constexpr double kStripTentHalfWidth = 2.0;
inline glm::dvec3 stripJointTotals(double y) {
  glm::dvec3 w;
  for (int j = 0; j < 3; ++j) w[j] = std::max(0.0, kStripTentHalfWidth - std::abs(y - (j + 0.5) * kStripBoneLength));
  return w / (w.x + w.y + w.z);
}
inline glm::dvec3 stripJointTotals(int row) { return stripJointTotals(row * kStripRowSpacing); }
// World position of joint j at the bind pose: the pivot of its rotation and scale.
inline glm::dvec3 stripJointBindWorld(int joint) {
  return glm::dvec3(stripRootMatrix() * glm::dvec4(0.0, joint * kStripBoneLength, 0.0, 1.0));
}

// Animation "bend" (index 0), duration 2 s; the three channels act in disjoint time ranges so each can be
// tested alone, and at t = 0 and t = 1.5 every joint is at its bind transform. joint1 rotation about its
// local Z, LINEAR: 0 deg at 0 s, 60 deg at 0.5 s, 0 deg at 1 s (stored as the quaternion (0,0,0,-1), so only
// a shortest-path slerp gives 30 deg at 0.75 s), then held.
inline constexpr std::array<double, 3> kStripRotationTimes{0.0, 0.5, 1.0};
inline constexpr std::array<double, 3> kStripRotationDegrees{0.0, 60.0, 0.0};
// joint2 translation, STEP: x offset 0 from 0 s, kStripStepOffsetX from 1 s, 0 again from 1.5 s (y stays 1).
inline constexpr std::array<double, 3> kStripTranslationTimes{0.0, 1.0, 1.5};
inline constexpr double kStripStepOffsetX = 0.3;
// joint2 uniform scale, CUBICSPLINE: 1 at 1.5 s (out-tangent kStripScaleOutTangent0 per second), 1.5 at 1.75
// s, 1 at 2 s; the other tangents are zero. Before 1.5 s the first key holds.
inline constexpr std::array<double, 3> kStripScaleTimes{1.5, 1.75, 2.0};
inline constexpr std::array<double, 3> kStripScaleValues{1.0, 1.5, 1.0};
inline constexpr double kStripScaleOutTangent0 = 2.0;
inline constexpr double kStripDuration = 2.0;
// In the bad-joint fixture, JOINTS_0[0] of this vertex equals kStripJointCount; in the zero-weight one, all 8
// weights of kStripZeroWeightVertex are zero.
inline constexpr int kStripBadJointVertex = 7;
inline constexpr int kStripZeroWeightVertex = 5;

// ---- Morph cube (writeMorphCube) ----
// Nodes (both scene roots, in this order, each instancing mesh 0): 0 "cube" (animated by the LINEAR sampler),
// 1 "cube_spline" (animated by the CUBICSPLINE sampler, and carrying node weights). Instance order: node 0,
// node 1. One node per sampler because a glTF animation may target a node's weights only once.
inline constexpr int kCubeVertexCount = 24;  // 6 faces x 4, faces in the order +X, -X, +Y, -Y, +Z, -Z
inline constexpr int kCubeTargetCount = 2;
inline constexpr std::array<double, 2> kCubeMeshWeights{0.25, 0.0};        // used by node 0 at rest
inline constexpr std::array<double, 2> kCubeSplineNodeWeights{0.0, 0.75};  // node 1's own weights, used at rest
inline glm::dvec3 cubeNodeTranslation(int node) { return node == 0 ? glm::dvec3(-1.5, 0, 0) : glm::dvec3(1.5, 0, 0); }
inline glm::dquat cubeNodeRotation(int node) {
  return node == 0 ? glm::angleAxis(glm::radians(45.0), glm::dvec3(0, 1, 0)) : glm::dquat(1, 0, 0, 0);
}
inline glm::dvec3 cubeFaceNormal(int face) {
  glm::dvec3 n(0.0);
  n[face / 2] = face % 2 == 0 ? 1.0 : -1.0;
  return n;
}
inline glm::dvec3 cubePosition(int vertex) {
  const glm::dvec3 n = cubeFaceNormal(vertex / 4);
  const glm::dvec3 u = std::abs(n.y) > 0.5 ? glm::dvec3(1, 0, 0) : glm::dvec3(0, 1, 0);
  const glm::dvec3 v = glm::cross(n, u);
  const double su[4] = {-1, 1, 1, -1}, sv[4] = {-1, -1, 1, 1};
  return 0.5 * (n + su[vertex % 4] * u + sv[vertex % 4] * v);
}
// Target 0 (dense): the top half moves up 0.5; +X face normals tilt towards +Y.
// Target 1 (POSITION sparse, no bufferView): the +X face (vertices 0..3) moves +0.3 in X; +Y face normals
// tilt to +X.
inline glm::dvec3 cubePositionDelta(int target, int vertex) {
  if (target == 0) return cubePosition(vertex).y > 0 ? glm::dvec3(0, 0.5, 0) : glm::dvec3(0.0);
  return vertex / 4 == 0 ? glm::dvec3(0.3, 0, 0) : glm::dvec3(0.0);
}
inline glm::dvec3 cubeNormalDelta(int target, int vertex) {
  if (target == 0) return vertex / 4 == 0 ? glm::dvec3(0, 0.5, 0) : glm::dvec3(0.0);
  return vertex / 4 == 2 ? glm::dvec3(0.5, 0, 0) : glm::dvec3(0.0);
}
// Animation "morph" (index 0), duration 2 s. Node 0, LINEAR: {0, 0} at 0 s -> {1, 0.5} at 1 s, then held.
// Node 1, CUBICSPLINE: key 1 s: value {0, 0}, out-tangent {1, 0}; key 2 s: in-tangent {0, 2}, value {1, 1};
// other tangents zero. Before 1 s its first key holds. At 1.5 s it gives {0.625, 0.25} (linear would be 0.5,
// 0.5).
inline constexpr std::array<double, 2> kCubeLinearTimes{0.0, 1.0};
inline constexpr std::array<std::array<double, 2>, 2> kCubeLinearWeights{{{0.0, 0.0}, {1.0, 0.5}}};
inline constexpr std::array<double, 2> kCubeSplineTimes{1.0, 2.0};
// Per key: in-tangent, value, out-tangent (the glTF layout), each {w0, w1}.
inline constexpr std::array<std::array<std::array<double, 2>, 3>, 2> kCubeSplineKeys{
    {{{{0.0, 0.0}, {0.0, 0.0}, {1.0, 0.0}}}, {{{0.0, 2.0}, {1.0, 1.0}, {0.0, 0.0}}}}};
inline constexpr double kCubeDuration = 2.0;

}  // namespace pose_reference::fixture
