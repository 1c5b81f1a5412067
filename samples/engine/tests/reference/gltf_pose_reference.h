// An independent, double-precision CPU implementation of glTF 2.0 posing (node hierarchy, animation samplers,
// morph targets, linear-blend skinning), written from the glTF 2.0 spec and not from the sample engine, so
// tests can use it as the ground truth for the engine's GPU skinning.
//
// Conventions (the spec leaves these to the implementation; the engine must match them to compare equal):
// - Looping: the animation's local time is fmod(time, duration), duration = the largest input time over all
// of
//   its samplers; so time == duration poses the first frame, not the last.
// - Skinning weights are used as stored (not renormalized); a vertex whose 8 weights are all zero is an
// error.
// - Skinned normals use the inverse-transpose of the upper 3x3 of the weight-blended joint matrix, then
// normalize.
// - Morph weights: the animation's `weights` channel when the played animation targets the node, else the
// node's
//   `weights`, else the mesh's `weights`, else zeros.
// - Only TRIANGLES primitives (mode 4 or absent) are posed; others are skipped (no entry in the result). At
// most
//   two influence sets (JOINTS_0/WEIGHTS_0 and JOINTS_1/WEIGHTS_1); a JOINTS_2 is reported as an error.
// - A node that has a `matrix` and is targeted by the played animation is an error (the spec forbids it).
//
// Thread safety: the functions are reentrant (no shared state); each call loads the file itself.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include <glm/glm.hpp>

namespace pose_reference {

struct PosedPrimitive {
  int node = -1;                           // glTF node index that holds the mesh
  int mesh = -1;                           // glTF mesh index
  int primitive = -1;                      // primitive index within the mesh (TRIANGLES primitives only)
  glm::dmat4 nodeWorld{1.0};               // the node's world transform at that time
  std::vector<glm::dvec3> worldPositions;  // posed (morphed, then skinned), world space
  std::vector<glm::dvec3> localPositions;  // inverse(nodeWorld) * world position (the engine's deformed-buffer space)
  std::vector<glm::dvec3> worldNormals;    // posed normals, normalized, world space; empty without NORMAL
  std::vector<uint32_t> indices;           // triangle list (generated 0..n-1 when the primitive has none)
};

// Evaluates the default scene (else scene 0, else all root nodes) of a .gltf/.glb at `time` seconds (finite,
// >= 0) of animation `animation` (index; -1 = rest pose: node transforms as stored, no animation), the time
// looping over that animation's duration. Order: scene roots in order, depth-first pre-order over children, a
// node's TRIANGLES primitives in order — the order in which the engine's loader creates Scene::instances.
// Returns std::nullopt and sets *error (when non-null) on unreadable files and bad input, naming the value:
// an animation index out of range, a joint index >= the skin's joint count, all-zero weights of a skinned
// vertex, ...
std::optional<std::vector<PosedPrimitive>> poseGltf(const std::string& path, int animation, double time,
                                                    std::string* error);

// The names of the file's animations in index order ("" for unnamed ones); empty when the file cannot be
// read.
std::vector<std::string> animationNames(const std::string& path);

}  // namespace pose_reference
