// The refit-quality measure of dynamic BLASes: a compute pass (shaders/blas_cluster_bounds.comp) that writes
// the AABB surface area of every cluster of kRefitClusterTriangles consecutive triangles, read back by the host.
#pragma once

#include <cstddef>
#include <cstdint>

#include "compute_pipeline.h"
#include "mesh_validation.h"
#include "pass_constants.h"

namespace rb {

class ClusterBoundsPass {
 public:
  Status create(Context& ctx);
  void destroy(Context& ctx);
  // False when the shader cannot read the mesh (a position or index address that is not 4-byte aligned, or a
  // 16-bit index buffer whose last word would be read past its end, or a mesh too large for the shader's 32-bit
  // indexing: over 715,827,882 triangles or 8 GiB of positions): such a mesh is rebuilt by refit count only.
  static bool canMeasure(const MeshDesc& mesh);
  static uint32_t clusterCount(uint32_t triangleCount);
  // Writes clusterCount(triangleCount) floats at `clusterAreas` (4-byte aligned device address).
  void record(Context& ctx, VkCommandBuffer cmd, const MeshDesc& mesh, VkDeviceAddress clusterAreas) const;

 private:
  ComputePipeline pipeline_;
};

}  // namespace rb
