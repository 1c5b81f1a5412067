// AccelerationStructureService::updateDynamicMeshes: the per-frame dynamic-mesh calls in their required order.
#include <raybridge/acceleration_structures.h>

namespace rb {

Status AccelerationStructureService::updateDynamicMeshes(std::span<const MeshHandle> meshes,
                                                         const AsyncBuildWait& ready,
                                                         std::vector<VkSemaphoreSubmitInfo>* tlasWaits,
                                                         std::vector<VkSemaphoreSubmitInfo>* vertexReuseWaits) {
  for (MeshHandle mesh : meshes)
    if (Status s = updateMesh(mesh); !s) return s;
  if (Status s = submitDynamicWork(ready); !s) return s;
  VkSemaphoreSubmitInfo wait{VK_STRUCTURE_TYPE_SEMAPHORE_SUBMIT_INFO};
  if (tlasWaits && fillTlasWait(wait)) tlasWaits->push_back(wait);
  if (vertexReuseWaits && fillVertexReuseWait(wait)) vertexReuseWaits->push_back(wait);
  return {};
}

}  // namespace rb
