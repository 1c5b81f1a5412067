// AccelerationStructureService::updateDynamicMeshes: the per-frame dynamic-mesh calls in their required order.
#include <raybridge/acceleration_structures.h>

#include <string>

namespace rb {

Status AccelerationStructureService::updateDynamicMeshes(std::span<const MeshHandle> meshes,
                                                         const AsyncBuildWait& ready,
                                                         std::vector<VkSemaphoreSubmitInfo>* tlasWaits,
                                                         std::vector<VkSemaphoreSubmitInfo>* vertexReuseWaits,
                                                         std::span<const MeshBounds> poseBounds) {
  if (!poseBounds.empty() && poseBounds.size() != meshes.size()) {
    return Error{ErrorCode::InvalidArgument, VK_SUCCESS,
                 "updateDynamicMeshes: poseBounds has " + std::to_string(poseBounds.size()) + " boxes for " +
                     std::to_string(meshes.size()) + " meshes; give one per mesh, or none"};
  }
  for (size_t i = 0; i < meshes.size(); ++i) {
    MeshUpdate update;
    if (!poseBounds.empty()) update.bounds = poseBounds[i];
    if (Status s = updateMesh(meshes[i], update); !s) return s;
  }
  if (Status s = submitDynamicWork(ready); !s) return s;
  VkSemaphoreSubmitInfo wait{VK_STRUCTURE_TYPE_SEMAPHORE_SUBMIT_INFO};
  if (tlasWaits && fillTlasWait(wait)) tlasWaits->push_back(wait);
  if (vertexReuseWaits && fillVertexReuseWait(wait)) vertexReuseWaits->push_back(wait);
  return {};
}

}  // namespace rb
