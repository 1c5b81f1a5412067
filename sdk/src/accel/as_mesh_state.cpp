// What the acceleration-structure service reports about a mesh's BLAS and what changes it outside builds: its state
// (MeshState) and address, failed builds and their retries, and eviction (evictMesh) with re-queuing.
#include <raybridge/acceleration_structures.h>

#include <algorithm>
#include <mutex>
#include <string>
#include <utility>

#include "as_service_impl.h"

namespace rb {

std::string AccelerationStructureService::Impl::meshName(const BlasEntry& e) const {
  if (!e.mesh.debugName.empty()) return "mesh '" + e.mesh.debugName + "'";
  const uint32_t r = e.sourceRegistration;
  const uint32_t generation = r < registrations.size() ? registrations[r].generation : 0;
  return "mesh {index " + std::to_string(r) + ", generation " + std::to_string(generation) +
         "} (MeshDesc::debugName names it)";
}

void AccelerationStructureService::Impl::markBuildFailed(uint32_t index, Error error) {
  BlasEntry& e = entries[index];
  e.state = BlasState::Failed;
  e.failure = std::move(error);
  if (std::find(failedBuilds.begin(), failedBuilds.end(), index) == failedBuilds.end()) failedBuilds.push_back(index);
}

void AccelerationStructureService::Impl::evictEntry(uint32_t index) {
  BlasEntry& e = entries[index];
  queue.erase(std::remove(queue.begin(), queue.end(), index), queue.end());
  failedBuilds.erase(std::remove(failedBuilds.begin(), failedBuilds.end(), index), failedBuilds.end());
  if (e.as) {
    VkAccelerationStructureKHR as = e.as;
    StorageAllocation alloc = e.storage;
    retire([this, as, alloc] {
      c.vk.vkDestroyAccelerationStructureKHR(c.desc.device, as, c.allocator());
      storage.free(alloc);
    });
  }
  if (e.state == BlasState::Built) {
    ++counters.meshEvictions;
    counters.evictedBlasBytes += e.currentSize;
  }
  reservedBytes -= e.reserved;
  e.reserved = 0;
  e.as = VK_NULL_HANDLE;
  e.storage = StorageAllocation{};
  e.address = 0;
  e.builtSize = e.currentSize = 0;
  e.compactionPending = false;
  e.compactedSize = 0;
  e.compacted = false;
  e.failure = Error{};
  // Queries of its last build still in flight (compacted sizes) must not apply to a later build.
  e.generation = e.generation + 1 == 0 ? 1 : e.generation + 1;
  e.state = BlasState::Evicted;
}

Status AccelerationStructureService::Impl::requeueEvicted(uint32_t index, const std::string& forWhat) {
  BlasEntry& e = entries[index];
  const VkDeviceSize need = storageNeed(e);
  if (Status st = makeRoom(need, forWhat); !st) return st;
  e.reserved = need;
  reservedBytes += need;
  e.state = BlasState::Queued;
  e.failure = Error{};
  queue.push_back(index);
  return {};
}

void AccelerationStructureService::Impl::retryFailedBuilds(Status& failure) {
  std::vector<uint32_t> waiting = std::move(failedBuilds);
  failedBuilds.clear();
  for (uint32_t index : waiting) {
    BlasEntry& e = entries[index];
    if (e.state != BlasState::Failed) continue;
    if (e.reserved == 0) {
      // Failed for the budget: it holds none of it until room is made.
      const VkDeviceSize need = storageNeed(e);
      if (Status st = makeRoom(need, "retrying the build of the " + meshName(e)); !st) {
        if (failure) failure = st;
        markBuildFailed(index, st.error());
        continue;
      }
      e.reserved = need;
      reservedBytes += need;
    }
    queue.push_back(index);
  }
}

Status AccelerationStructureService::evictMesh(MeshHandle mesh) {
  Impl& s = *impl_;
  RegistrationLock lock(s);
  Result<Registration*> r = s.lookup(mesh, "evictMesh");
  if (!r) return r.error();
  const uint32_t index = r.value()->blas;
  const BlasEntry& e = s.entries[index];
  if (e.mesh.desc.role == MeshRole::Dynamic) {
    return Error{ErrorCode::InvalidArgument, VK_SUCCESS,
                 "evictMesh: " + s.meshName(e) +
                     " is dynamic (MeshRole::Dynamic): its BLAS copies are rebuilt from the engine's vertex buffers "
                     "as it deforms, so it cannot be evicted; release it (releaseMesh) instead"};
  }
  if (e.state != BlasState::Evicted) s.evictEntry(index);
  return {};
}

Result<MeshStatus> AccelerationStructureService::meshState(MeshHandle mesh) const {
  std::lock_guard<std::mutex> lock(impl_->mutex);
  Result<Registration*> r = impl_->lookup(mesh, "meshState");
  if (!r) return r.error();
  const BlasEntry& e = impl_->entries[r.value()->blas];
  MeshStatus out;
  switch (e.state) {
    case BlasState::Built: out.state = MeshState::Built; break;
    case BlasState::Failed:
      out.state = MeshState::Failed;
      out.error = e.failure;
      break;
    case BlasState::Evicted: out.state = MeshState::Evicted; break;
    case BlasState::Free:  // a live registration never names a free entry
    case BlasState::Queued: out.state = MeshState::Queued; break;
  }
  return out;
}

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
  switch (e.state) {
    case BlasState::Built: return e.address;
    case BlasState::Failed:
      return Error{ErrorCode::NotReady, VK_SUCCESS,
                   "blasAddress: the build of the " + impl_->meshName(e) + " failed (" + e.failure.message + ")"};
    case BlasState::Evicted:
      return Error{ErrorCode::NotReady, VK_SUCCESS,
                   "blasAddress: the " + impl_->meshName(e) +
                       " was evicted (evictMesh); a TLAS build that references it builds it again"};
    default:
      return Error{ErrorCode::NotReady, VK_SUCCESS, "blasAddress: the mesh's BLAS build has not been recorded yet"};
  }
}

}  // namespace rb

namespace rb {

void AccelerationStructureService::meshChanges(std::span<const Instance> instances, std::span<MeshChange> out) const {
  Impl& s = *impl_;
  std::lock_guard<std::mutex> lock(s.mutex);
  const size_t n = std::min(instances.size(), out.size());
  for (size_t i = 0; i < n; ++i) {
    const MeshHandle h = instances[i].mesh;
    out[i] = {};
    if (h.isNull() || h.index >= s.registrations.size()) continue;
    const Registration& reg = s.registrations[h.index];
    if (!reg.live || reg.generation != h.generation) continue;
    out[i].poseBounds = reg.poseBounds.given();
    out[i].bounds = out[i].poseBounds ? reg.poseBounds : reg.mesh.desc.bounds;
    out[i].poses = s.entries[reg.blas].dyn.pose;
  }
}

}  // namespace rb
