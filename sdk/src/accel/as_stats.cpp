// Statistics of the acceleration-structure service: BLAS counts and sizes, storage, scratch and TLAS memory,
// build timings.
#include <raybridge/acceleration_structures.h>

#include <mutex>

#include "as_service_impl.h"

namespace rb {

uint32_t AccelerationStructureService::nonOpaqueMeshCount() const {
  Impl& s = *impl_;
  std::lock_guard<std::mutex> lock(s.mutex);
  uint32_t count = 0;
  for (const Registration& r : s.registrations) count += r.live && r.mesh.desc.nonOpaque;
  return count;
}

AsStats AccelerationStructureService::stats() const {
  Impl& s = *impl_;
  std::lock_guard<std::mutex> lock(s.mutex);
  s.handOnDeferredRetires();
  s.resolveBatches();
  s.resolveDynamicSubmissions();
  AsStats out = s.counters;
  out.meshHandles = s.liveRegistrations();
  out.nonOpaqueMeshes = 0;
  for (const Registration& r : s.registrations) out.nonOpaqueMeshes += r.live && r.mesh.desc.nonOpaque;
  out.blasCount = out.blasQueued = out.blasFailed = out.blasEvicted = 0;
  out.triangles = out.blasBytes = out.blasBytesBeforeCompaction = out.dynamicBlasBytes = 0;
  for (uint32_t i = 1; i < s.entries.size(); ++i) {
    const BlasEntry& e = s.entries[i];
    if (e.state == BlasState::Free) continue;
    if (e.state == BlasState::Failed || e.state == BlasState::Evicted) {
      ++(e.state == BlasState::Failed ? out.blasFailed : out.blasEvicted);
      continue;
    }
    ++out.blasCount;
    if (e.state == BlasState::Queued) {
      ++out.blasQueued;
      continue;
    }
    out.triangles += e.mesh.desc.triangleCount;
    const VkDeviceSize copies = e.mesh.desc.role == MeshRole::Dynamic ? e.dyn.copies.size() : 1;
    out.blasBytesBeforeCompaction += e.builtSize * copies;
    out.blasBytes += e.currentSize * copies;
    if (e.mesh.desc.role == MeshRole::Dynamic) out.dynamicBlasBytes += e.currentSize * copies;
  }
  out.bytesPerTriangle = out.triangles ? double(out.blasBytes) / double(out.triangles) : 0.0;
  out.storageBlocks = s.storage.blockCount();
  out.storageBlockBytes = s.storage.blockBytes();
  out.storageUsedBytes = s.storage.usedBytes();
  if (s.dynamicStorage) {
    out.storageBlocks += s.dynamicStorage->blockCount();
    out.storageBlockBytes += s.dynamicStorage->blockBytes();
    out.storageUsedBytes += s.dynamicStorage->usedBytes();
  }
  out.scratchBytes = s.scratch.allocatedBytes + s.asyncScratch.allocatedBytes;
  out.tlasBytes = 0;
  for (const TlasSlot& t : s.tlasSlots) {
    out.tlasBytes += t.storage.allocatedBytes + t.scratch.allocatedBytes + t.instances.allocatedBytes +
                     t.deviceInstances.allocatedBytes + t.shading.allocatedBytes + t.deviceShading.allocatedBytes;
  }
  out.batches = s.timings;
  return out;
}

}  // namespace rb
