// The refit-quality measure of dynamic BLASes: a compute pass (shaders/blas_cluster_bounds.comp) that writes
// the AABB surface area of every cluster of kRefitClusterTriangles consecutive triangles, read back by the host.
#pragma once

#include <cstddef>
#include <cstdint>

#include "compute_pipeline.h"
#include "mesh_validation.h"

namespace rb {

// Mirrors ClusterBoundsConstants in shaders/blas_cluster_bounds.comp.
struct ClusterBoundsConstants {
  uint64_t positions;
  uint64_t indices;
  uint64_t clusterAreas;
  uint32_t positionStride;
  uint32_t positionFormat;  // ClusterPositionFormat
  uint32_t indexType;       // 0 u32, 1 u16, 2 none
  uint32_t triangleCount;
  uint32_t firstCluster;
  uint32_t pad;
};
static_assert(sizeof(ClusterBoundsConstants) == 48, "must match shaders/blas_cluster_bounds.comp");
static_assert(offsetof(ClusterBoundsConstants, positionStride) == 24, "must match shaders/blas_cluster_bounds.comp");

class ClusterBoundsPass {
 public:
  Status create(Context& ctx);
  void destroy(Context& ctx);
  // False when the shader cannot read the mesh (a position or index address that is not 4-byte aligned, or a
  // 16-bit index buffer whose last word would be read past its end): such a mesh is rebuilt by refit count only.
  static bool canMeasure(const MeshDesc& mesh);
  static uint32_t clusterCount(uint32_t triangleCount);
  // Writes clusterCount(triangleCount) floats at `clusterAreas` (4-byte aligned device address).
  void record(Context& ctx, VkCommandBuffer cmd, const MeshDesc& mesh, VkDeviceAddress clusterAreas) const;

 private:
  ComputePipeline pipeline_;
};

}  // namespace rb
