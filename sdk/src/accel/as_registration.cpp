// Mesh registration of the acceleration-structure service: registration and content-hash dedup, release, and the
// BLAS memory budget with its least-recently-used eviction of cached BLASes.
#include <raybridge/acceleration_structures.h>

#include <algorithm>
#include <string>
#include <utility>

#include "as_service_impl.h"

namespace rb {

void AccelerationStructureService::Impl::destroyEntry(uint32_t index) {
  BlasEntry& e = entries[index];
  auto it = byKey.find(e.key);
  if (it != byKey.end() && it->second == index) byKey.erase(it);
  queue.erase(std::remove(queue.begin(), queue.end(), index), queue.end());
  failedBuilds.erase(std::remove(failedBuilds.begin(), failedBuilds.end(), index), failedBuilds.end());
  if (e.mesh.desc.role == MeshRole::Dynamic) {
    retireCopies(e.dyn.copies);  // `as` only mirrors the newest copy
  } else if (e.as) {
    VkAccelerationStructureKHR as = e.as;
    StorageAllocation alloc = e.storage;
    retire([this, as, alloc] {
      c.vk.vkDestroyAccelerationStructureKHR(c.desc.device, as, c.allocator());
      storage.free(alloc);
    });
  }
  reservedBytes -= e.reserved;
  uint32_t generation = e.generation + 1;
  e = BlasEntry{};
  e.generation = generation == 0 ? 1 : generation;
  freeSlots.push_back(index);
}

uint32_t AccelerationStructureService::Impl::cachedVictim() const {
  uint32_t victim = 0;
  uint64_t oldest = UINT64_MAX;
  for (uint32_t i = 1; i < entries.size(); ++i) {
    const BlasEntry& e = entries[i];
    if (e.state == BlasState::Free || e.refCount > 0) continue;
    bool inLatestTlas = e.lastTlasSerial != 0 && e.lastTlasSerial == tlasSerial;
    // Not c.frame: registerMesh may run while the recording thread is in Context::beginFrame.
    bool inFlight = e.lastTlasSerial != 0 && !frameKnownDone(e.lastUsedFrame);
    if (inLatestTlas || inFlight) continue;
    if (e.releasedOrder < oldest) {
      oldest = e.releasedOrder;
      victim = i;
    }
  }
  return victim;
}

void AccelerationStructureService::Impl::trimReleasedCache() {
  VkDeviceSize cached = 0;
  for (uint32_t i = 1; i < entries.size(); ++i)
    if (entries[i].state != BlasState::Free && entries[i].refCount == 0) cached += entries[i].reserved;
  while (cached > releasedCacheCap) {
    const uint32_t victim = cachedVictim();
    if (victim == 0) return;  // the rest is in flight: a later call frees it
    cached -= entries[victim].reserved;
    destroyEntry(victim);
    ++counters.evictions;
  }
}

Status AccelerationStructureService::Impl::makeRoom(VkDeviceSize bytes, const std::string& forWhat) {
  if (desc.blasBudgetBytes == 0) return {};
  while (reservedBytes + bytes > desc.blasBudgetBytes) {
    const uint32_t victim = cachedVictim();
    if (victim == 0) {
      return Error{ErrorCode::OutOfBudget, VK_SUCCESS,
                   forWhat + " needs " + std::to_string(bytes) + " bytes of BLAS storage but the budget of " +
                       std::to_string(desc.blasBudgetBytes) + " bytes has " + std::to_string(reservedBytes) +
                       " bytes held by meshes that are registered or referenced by a TLAS in flight; raise "
                       "AsServiceDesc::blasBudgetBytes or release meshes"};
    }
    destroyEntry(victim);
    ++counters.evictions;
  }
  return {};
}

Result<MeshHandle> AccelerationStructureService::registerMesh(const MeshDesc& desc) {
  Impl& s = *impl_;
  // Validation, the content hash and the size query read only immutable state: done before taking the lock.
  Result<ValidatedMesh> v = validateMesh(desc, s.c.vk, s.c.desc.physicalDevice, s.c.info.maxPrimitiveCount);
  if (!v) return v.error();
  BlasEntry e;
  e.mesh = v.value();
  e.key = v->key;
  s.queryBuildSizes(e);
  const VkDeviceSize need = s.storageNeed(e);
  const std::string name = desc.debugName ? std::string("mesh '") + desc.debugName + "'" : "a mesh";

  RegistrationLock lock(s);
  // The registration itself: its own handle, buffers and lifetime, whatever BLAS it ends up sharing.
  auto addRegistration = [&](uint32_t blas) {
    uint32_t r;
    if (!s.freeRegistrations.empty()) {
      r = s.freeRegistrations.back();
      s.freeRegistrations.pop_back();
    } else {
      r = static_cast<uint32_t>(s.registrations.size());
      s.registrations.emplace_back();
    }
    Registration& reg = s.registrations[r];
    reg.generation = reg.generation + 1 == 0 ? 1 : reg.generation + 1;
    reg.live = true;
    reg.blas = blas;
    reg.mesh = v.value();
    ++s.entries[blas].refCount;
    ++s.counters.registrations;
    return MeshHandle{r, reg.generation};
  };
  bool dedupable = v->desc.role == MeshRole::Static || v->desc.contentKey != 0;
  if (dedupable) {
    if (auto it = s.byKey.find(v->key); it != s.byKey.end()) {
      // An evicted BLAS is built again for the new registration, if the budget can hold it.
      if (s.entries[it->second].state == BlasState::Evicted) {
        if (Status st = s.requeueEvicted(it->second, "registering " + name + " (sharing an evicted BLAS)"); !st) {
          return st.error();
        }
      }
      ++s.counters.dedupHits;
      BlasEntry& shared = s.entries[it->second];
      MeshHandle h = addRegistration(it->second);
      // A cached BLAS (all registrations released) reads from the new one's buffers from now on.
      if (shared.refCount == 1) {
        shared.mesh = v.value();
        shared.sourceRegistration = h.index;
      }
      return h;
    }
  }
  if (Status st = s.makeRoom(need, "registering " + name); !st) return st.error();

  uint32_t index;
  if (!s.freeSlots.empty()) {
    index = s.freeSlots.back();
    s.freeSlots.pop_back();
    e.generation = s.entries[index].generation;
  } else {
    index = static_cast<uint32_t>(s.entries.size());
    s.entries.emplace_back();
    e.generation = 1;
  }
  e.state = BlasState::Queued;
  e.refCount = 0;
  e.reserved = need;
  s.entries[index] = e;
  // Dynamic meshes are built by the dynamic work (their copies, their queue); the queue holds static builds.
  if (e.mesh.desc.role == MeshRole::Static) s.queue.push_back(index);
  if (dedupable) s.byKey[e.key] = index;
  s.reservedBytes += need;
  MeshHandle h = addRegistration(index);
  s.entries[index].sourceRegistration = h.index;
  return h;
}

Status AccelerationStructureService::releaseMesh(MeshHandle mesh) {
  Impl& s = *impl_;
  RegistrationLock lock(s);
  Result<Registration*> r = s.lookup(mesh, "releaseMesh");
  if (!r) return r.error();
  const uint32_t index = r.value()->blas;
  r.value()->live = false;
  r.value()->mesh = ValidatedMesh{};
  s.freeRegistrations.push_back(mesh.index);
  BlasEntry& entry = s.entries[index];
  if (--entry.refCount > 0) {
    if (entry.sourceRegistration == mesh.index) {
      // Builds and refits must not read the released registration's buffers: take another live one's.
      for (uint32_t i = 1; i < s.registrations.size(); ++i) {
        if (s.registrations[i].live && s.registrations[i].blas == index) {
          entry.mesh = s.registrations[i].mesh;
          entry.sourceRegistration = i;
          break;
        }
      }
    }
    return {};
  }
  bool cacheable = s.byKey.count(entry.key) && s.byKey[entry.key] == index;
  if (entry.state != BlasState::Built || !cacheable) {
    // Nothing to gain from keeping it: not built (queued, failed or evicted), or (dynamic) no registration can ever
    // match it again.
    s.destroyEntry(index);
  } else {
    entry.releasedOrder = ++s.releaseCounter;
    s.trimReleasedCache();
  }
  return {};
}

}  // namespace rb
