// What the acceleration-structure service reports about a mesh's BLAS: its state and its address.
#include <raybridge/acceleration_structures.h>

#include <mutex>

#include "as_service_impl.h"

namespace rb {

Result<bool> AccelerationStructureService::isBuilt(MeshHandle mesh) const {
  std::lock_guard<std::mutex> lock(impl_->mutex);
  impl_->handOnDeferredRetires();
  Result<Registration*> r = impl_->lookup(mesh, "isBuilt");
  if (!r) return r.error();
  return impl_->entries[r.value()->blas].state == BlasState::Built;
}

Result<VkDeviceAddress> AccelerationStructureService::blasAddress(MeshHandle mesh) const {
  std::lock_guard<std::mutex> lock(impl_->mutex);
  impl_->handOnDeferredRetires();
  Result<Registration*> r = impl_->lookup(mesh, "blasAddress");
  if (!r) return r.error();
  const BlasEntry& e = impl_->entries[r.value()->blas];
  if (e.state != BlasState::Built) {
    return Error{ErrorCode::NotReady, VK_SUCCESS, "blasAddress: the mesh's BLAS build has not been recorded yet"};
  }
  return e.address;
}

}  // namespace rb
