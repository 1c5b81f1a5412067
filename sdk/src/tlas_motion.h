// The host-side refit-quality measure of TlasBuildMode::Adaptive: how far the instances drifted apart since the
// TLAS was last rebuilt.
//
// A refit keeps the tree's topology: instances that were neighbours at the rebuild stay in the same subtrees
// however far they move, so the boxes of those subtrees grow and rays visit more of them. At a rebuild the
// instances are grouped by a uniform grid over their origins (about kTlasClusterInstances per occupied cell: a
// stand-in for the tree's lower nodes, which the driver does not expose); each frame the summed surface area of
// each group's bounding box is compared with its value at the rebuild. An instance counts as a cube of half a cell
// edge around its origin under its own rotation and scale (the mesh's extent is not known here; the cell is the
// scale of its neighbourhood), so a group that moves together (a vehicle, a crowd walking one way, a
// camera-relative origin shift) keeps its area, while members that scatter, spin (a rotated box's bounds are up to
// sqrt(3) times wider) or grow enlarge it, as they enlarge the refitted tree's boxes.
//
// Thread safety: none; owned by one service, used under its mutex.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

namespace rb {

// Instances per group of the measure, on average over the occupied cells.
inline constexpr uint32_t kTlasClusterInstances = 16;

class TlasMotionMeasure {
 public:
  // Floats per instance in the spans below: its row-major 3x4 object-to-world transform (VkTransformMatrixKHR).
  static constexpr size_t kFloatsPerInstance = 12;
  // Groups the instances at a rebuild and records the baseline area.
  void reset(std::span<const float> transforms);
  // The summed group area now over the one at the last reset(); 1 when no group grew. The instance count must
  // be the one of reset() (a refit's instance list keeps its count).
  double growth(std::span<const float> transforms);
  uint32_t refitsSinceRebuild = 0;

 private:
  double summedArea(std::span<const float> transforms);

  std::vector<uint32_t> groupOf_;  // per instance
  uint32_t groups_ = 0;
  float pad_ = 0.0f;  // half a cell edge
  double baseline_ = 0.0;
  std::vector<float> boxes_;  // per group: min xyz, max xyz (scratch of summedArea)
};

}  // namespace rb
