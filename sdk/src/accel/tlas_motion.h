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
// The grid spans the origins within the kOutlierFraction quantiles per axis; an instance more than a cell outside
// is a group of its own, so one far instance does not make the cells so large that the whole field is one group. A
// non-finite transform (at the rebuild or since) reads as unbounded growth, and so does any growth over a zero baseline
// (instances hidden by a zero scale): the policy rebuilds rather than refit over what it cannot measure.
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
  // The summed group area now over the one at the last reset(); 1 when no group grew; +inf when a transform
  // now or at reset() is not finite, or when the area grew from 0. A list of another instance count than
  // reset()'s gives 1 (no refit chain: a refit's instance list keeps its count).
  double growth(std::span<const float> transforms);
  uint32_t refitsSinceRebuild = 0;

 private:
  double summedArea(std::span<const float> transforms);

  // Per axis, the fraction of origins below the grid's low end and above its high end (1% each: for lists of
  // under 100 instances, none).
  static constexpr double kOutlierFraction = 0.01;
  // Origins per axis that the quantiles are taken from (an even stride over longer lists).
  static constexpr size_t kQuantileSamples = 1024;

  std::vector<uint32_t> groupOf_;  // per instance
  uint32_t groups_ = 0;
  double pad_ = 0.5;  // half a cell edge
  double baseline_ = 0.0;
  float ref_[3] = {0.0f, 0.0f, 0.0f};  // the grid's low corner: summedArea()'s boxes are relative to it
  bool finite_ = true;                 // every float of reset()'s list was finite
  std::vector<float> boxes_;           // per group: min xyz, max xyz relative to ref_ (scratch of summedArea)
};

}  // namespace rb
