// The BLAS side of the acceleration-structure service: registration and dedup, budgets and eviction, batched
// builds and refits, compaction, statistics.
#include <raybridge/acceleration_structures.h>

#include <algorithm>
#include <string>
#include <utility>

#include "align_up.h"
#include "as_service_impl.h"

namespace rb {

namespace {

// A compacted size that saves less than this share of the built size is not worth the copy (lavapipe reports the
// built size itself: every compaction there would copy for nothing).
constexpr VkDeviceSize kMinCompactionSavingPercent = 2;

constexpr VkDeviceSize kDefaultScratchBudget = 64ull << 20;
constexpr VkDeviceSize kDefaultBlockBytes = 32ull << 20;


}  // namespace

void recordAsBarrier(const DeviceFunctions& vk, VkCommandBuffer cmd, VkPipelineStageFlags dstStages) {
  VkMemoryBarrier barrier{VK_STRUCTURE_TYPE_MEMORY_BARRIER};
  barrier.srcAccessMask = VK_ACCESS_ACCELERATION_STRUCTURE_WRITE_BIT_KHR;
  barrier.dstAccessMask = VK_ACCESS_ACCELERATION_STRUCTURE_READ_BIT_KHR |
                          VK_ACCESS_ACCELERATION_STRUCTURE_WRITE_BIT_KHR;
  vk.vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_ACCELERATION_STRUCTURE_BUILD_BIT_KHR, dstStages, 0, 1, &barrier, 0,
                          nullptr, 0, nullptr);
}

AccelerationStructureService::Impl::Impl(Context& context, const AsServiceDesc& d)
    : ctx(context),
      c(internal::contextImpl(context)),
      desc(d),
      storage(context, d.storageBlockBytes ? d.storageBlockBytes : kDefaultBlockBytes) {
  if (desc.scratchBudgetBytes == 0) desc.scratchBudgetBytes = kDefaultScratchBudget;
  if (desc.storageBlockBytes == 0) desc.storageBlockBytes = kDefaultBlockBytes;
  tlasSlots.resize(c.desc.framesInFlight);
  entries.emplace_back();  // index 0 is never used, so a zero handle is always the null handle
  registrations.emplace_back();
}

AccelerationStructureService::Impl::~Impl() {
  // Contract: the GPU is done with everything this service recorded or submitted, on the engine's queues and on
  // the async queue (the SDK never waits). Retired objects reference the storage allocators, so they are released
  // before those go.
  handOnDeferredRetires();
  submitter.destroy();
  for (uint32_t i = 1; i < entries.size(); ++i) {
    if (entries[i].state != BlasState::Free) destroyEntry(i);
  }
  for (TlasSlot& s : tlasSlots) {
    if (s.tlas) c.vk.vkDestroyAccelerationStructureKHR(c.desc.device, s.tlas, c.allocator());
    destroyBuffer(ctx, s.storage);
    destroyBuffer(ctx, s.scratch);
    destroyBuffer(ctx, s.instances);
    destroyBuffer(ctx, s.deviceInstances);
    destroyBuffer(ctx, s.shading);
    destroyBuffer(ctx, s.deviceShading);
  }
  for (BuildBatch& b : inFlightBatches) {
    if (b.timestamps) c.vk.vkDestroyQueryPool(c.desc.device, b.timestamps, c.allocator());
    if (b.compactedSizes) c.vk.vkDestroyQueryPool(c.desc.device, b.compactedSizes, c.allocator());
  }
  for (VkQueryPool p : freeTimestampPools) c.vk.vkDestroyQueryPool(c.desc.device, p, c.allocator());
  destroyBuffer(ctx, scratch);
  destroyDynamic();
  c.releaseRetired(true);
}

void AccelerationStructureService::Impl::retire(std::function<void()> release) {
  if (deferRetires) {
    deferredRetires.push_back(std::move(release));
  } else {
    c.retire(std::move(release));
  }
}

void AccelerationStructureService::Impl::handOnDeferredRetires() {
  for (std::function<void()>& release : deferredRetires) c.retire(std::move(release));
  deferredRetires.clear();
}

VkDeviceSize AccelerationStructureService::Impl::scratchAlignment() const {
  return std::max<VkDeviceSize>(c.info.minAccelerationStructureScratchOffsetAlignment, 1);
}

VkDeviceSize AccelerationStructureService::Impl::storageNeed(const BlasEntry& e) const {
  const VkDeviceSize one = alignUp(e.sizes.accelerationStructureSize, AsStorageAllocator::kAlignment);
  return e.mesh.desc.role == MeshRole::Dynamic ? one * dynamicCopies : one;
}

VkBuildAccelerationStructureFlagsKHR AccelerationStructureService::Impl::blasFlags(const BlasEntry& e) const {
  if (e.mesh.desc.role == MeshRole::Dynamic) {
    return VK_BUILD_ACCELERATION_STRUCTURE_PREFER_FAST_BUILD_BIT_KHR |
           VK_BUILD_ACCELERATION_STRUCTURE_ALLOW_UPDATE_BIT_KHR;
  }
  VkBuildAccelerationStructureFlagsKHR f = VK_BUILD_ACCELERATION_STRUCTURE_PREFER_FAST_TRACE_BIT_KHR;
  if (!desc.disableCompaction) f |= VK_BUILD_ACCELERATION_STRUCTURE_ALLOW_COMPACTION_BIT_KHR;
  return f;
}

void AccelerationStructureService::Impl::queryBuildSizes(BlasEntry& e) const {
  VkAccelerationStructureGeometryKHR geometry;
  VkAccelerationStructureBuildRangeInfoKHR range;
  buildGeometry(e, geometry, range);
  VkAccelerationStructureBuildGeometryInfoKHR info{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_BUILD_GEOMETRY_INFO_KHR};
  info.type = VK_ACCELERATION_STRUCTURE_TYPE_BOTTOM_LEVEL_KHR;
  info.flags = blasFlags(e);
  info.mode = VK_BUILD_ACCELERATION_STRUCTURE_MODE_BUILD_KHR;
  info.geometryCount = 1;
  info.pGeometries = &geometry;
  c.vk.vkGetAccelerationStructureBuildSizesKHR(c.desc.device, VK_ACCELERATION_STRUCTURE_BUILD_TYPE_DEVICE_KHR, &info,
                                               &range.primitiveCount, &e.sizes);
}

Result<VkQueryPool> AccelerationStructureService::Impl::takeTimestampPool(std::vector<VkQueryPool>& pools,
                                                                          const char* what) {
  if (pools.empty()) {
    VkQueryPoolCreateInfo qi{VK_STRUCTURE_TYPE_QUERY_POOL_CREATE_INFO};
    qi.queryType = VK_QUERY_TYPE_TIMESTAMP;
    qi.queryCount = 2;
    VkQueryPool pool;
    VkResult r = c.vk.vkCreateQueryPool(c.desc.device, &qi, c.allocator(), &pool);
    if (r != VK_SUCCESS) return vulkanError(r, std::string("vkCreateQueryPool (") + what + ")");
    pools.push_back(pool);
  }
  VkQueryPool pool = pools.back();
  pools.pop_back();
  return pool;
}

void AccelerationStructureService::Impl::buildGeometry(const BlasEntry& e, VkAccelerationStructureGeometryKHR& g,
                                                       VkAccelerationStructureBuildRangeInfoKHR& range) const {
  const MeshDesc& m = e.mesh.desc;
  g = VkAccelerationStructureGeometryKHR{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_KHR};
  g.geometryType = VK_GEOMETRY_TYPE_TRIANGLES_KHR;
  g.flags = m.nonOpaque ? 0 : VK_GEOMETRY_OPAQUE_BIT_KHR;
  auto& t = g.geometry.triangles;
  t.sType = VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_TRIANGLES_DATA_KHR;
  t.vertexFormat = m.vertexFormat;
  t.vertexData.deviceAddress = m.vertexAddress;
  t.vertexStride = m.vertexStride;
  t.maxVertex = m.vertexCount - 1;
  t.indexType = m.indexType == IndexType::Uint32   ? VK_INDEX_TYPE_UINT32
                : m.indexType == IndexType::Uint16 ? VK_INDEX_TYPE_UINT16
                                                   : VK_INDEX_TYPE_NONE_KHR;
  t.indexData.deviceAddress = m.indexAddress;
  range = VkAccelerationStructureBuildRangeInfoKHR{};
  range.primitiveCount = m.triangleCount;
}

Result<VkAccelerationStructureKHR> AccelerationStructureService::Impl::createAs(VkAccelerationStructureTypeKHR type,
                                                                                VkBuffer buffer, VkDeviceSize offset,
                                                                                VkDeviceSize size) {
  VkAccelerationStructureCreateInfoKHR info{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_CREATE_INFO_KHR};
  info.buffer = buffer;
  info.offset = offset;
  info.size = size;
  info.type = type;
  VkAccelerationStructureKHR as = VK_NULL_HANDLE;
  VkResult r = c.vk.vkCreateAccelerationStructureKHR(c.desc.device, &info, c.allocator(), &as);
  if (r != VK_SUCCESS) return vulkanError(r, "vkCreateAccelerationStructureKHR");
  return as;
}

Result<Registration*> AccelerationStructureService::Impl::lookup(MeshHandle h, const char* what) {
  if (h.isNull()) {
    return Error{ErrorCode::InvalidArgument, VK_SUCCESS, std::string(what) + ": the mesh handle is null"};
  }
  if (h.index >= registrations.size() || registrations[h.index].generation != h.generation ||
      !registrations[h.index].live) {
    return Error{ErrorCode::StaleHandle, VK_SUCCESS,
                 std::string(what) + ": mesh handle {index " + std::to_string(h.index) + ", generation " +
                     std::to_string(h.generation) +
                     "} was released (releaseMesh) or never registered; register the mesh again to use it"};
  }
  return &registrations[h.index];
}

uint32_t AccelerationStructureService::Impl::liveRegistrations() const {
  uint32_t n = 0;
  for (const Registration& r : registrations) n += r.live ? 1u : 0u;
  return n;
}

void AccelerationStructureService::Impl::destroyEntry(uint32_t index) {
  BlasEntry& e = entries[index];
  auto it = byKey.find(e.key);
  if (it != byKey.end() && it->second == index) byKey.erase(it);
  if (e.state == BlasState::Queued) {
    queue.erase(std::remove(queue.begin(), queue.end(), index), queue.end());
  }
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

Status AccelerationStructureService::Impl::makeRoom(VkDeviceSize bytes, const std::string& forWhat) {
  if (desc.blasBudgetBytes == 0) return {};
  while (reservedBytes + bytes > desc.blasBudgetBytes) {
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

AccelerationStructureService::AccelerationStructureService(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
AccelerationStructureService::~AccelerationStructureService() = default;

Result<std::unique_ptr<AccelerationStructureService>> AccelerationStructureService::create(Context& context,
                                                                                           const AsServiceDesc& desc) {
  if (desc.storageBlockBytes != 0 && desc.storageBlockBytes < (1u << 16)) {
    return Error{ErrorCode::InvalidArgument, VK_SUCCESS,
                 "AsServiceDesc::storageBlockBytes is " + std::to_string(desc.storageBlockBytes) +
                     "; use 0 (32 MiB) or at least 64 KiB"};
  }
  auto impl = std::make_unique<Impl>(context, desc);
  if (Status st = impl->initDynamic(desc); !st) return st.error();
  return std::unique_ptr<AccelerationStructureService>(new AccelerationStructureService(std::move(impl)));
}

namespace {

// Held by registerMesh/releaseMesh: the service lock, and the Context's retire queue left alone (see
// AccelerationStructureService::Impl::deferRetires).
class RegistrationLock {
 public:
  explicit RegistrationLock(AccelerationStructureService::Impl& s) : s_(s), lock_(s.mutex) { s_.deferRetires = true; }
  ~RegistrationLock() { s_.deferRetires = false; }
  RegistrationLock(const RegistrationLock&) = delete;
  RegistrationLock& operator=(const RegistrationLock&) = delete;

 private:
  AccelerationStructureService::Impl& s_;
  std::lock_guard<std::mutex> lock_;
};

}  // namespace

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
  if (entry.state == BlasState::Queued || !cacheable) {
    // Nothing to gain from keeping it: never built, or (dynamic) no registration can ever match it again.
    s.destroyEntry(index);
  } else {
    entry.releasedOrder = ++s.releaseCounter;
  }
  return {};
}

void AccelerationStructureService::Impl::addTiming(const BuildBatchTiming& timing) {
  timings.push_back(timing);
  if (timings.size() > kMaxBatchTimings) {
    timings.erase(timings.begin());
    ++counters.batchTimingsDropped;
  }
}

void AccelerationStructureService::Impl::resolveBatches() {
  auto failed = [&](VkResult r, const char* what) {
    if (queryError) queryError = vulkanError(r, std::string("vkGetQueryPoolResults (") + what + ")");
  };
  std::vector<BuildBatch> keep;
  for (BuildBatch& b : inFlightBatches) {
    if (!c.frameDone(b.frame)) {
      keep.push_back(b);
      continue;
    }
    if (b.timestamps) {
      uint64_t ticks[2] = {0, 0};
      VkResult r = c.vk.vkGetQueryPoolResults(c.desc.device, b.timestamps, 0, 2, sizeof(ticks), ticks, sizeof(uint64_t),
                                              VK_QUERY_RESULT_64_BIT);
      if (r == VK_NOT_READY) {
        keep.push_back(b);
        continue;
      }
      if (r == VK_SUCCESS) {
        addTiming({b.frame, b.builds, b.triangles,
                   double(c.info.timestampTicks(ticks[0], ticks[1])) * c.info.timestampPeriodNs * 1e-6});
      } else {
        failed(r, "BLAS build timestamps");  // a lost device: the batch goes without a timing
      }
      freeTimestampPools.push_back(b.timestamps);
    }
    if (b.compactedSizes) {
      std::vector<uint64_t> sizes(b.compactEntries.size(), 0);
      VkResult r = c.vk.vkGetQueryPoolResults(c.desc.device, b.compactedSizes, 0, static_cast<uint32_t>(sizes.size()),
                                              sizes.size() * sizeof(uint64_t), sizes.data(), sizeof(uint64_t),
                                              VK_QUERY_RESULT_64_BIT);
      if (r == VK_SUCCESS) {
        for (size_t i = 0; i < sizes.size(); ++i) {
          BlasEntry& e = entries[b.compactEntries[i]];
          if (e.generation != b.compactGenerations[i] || e.state != BlasState::Built || !e.compactionPending) continue;
          e.compactionPending = false;
          // Lavapipe reports the built size: a copy would cost time and save nothing.
          if (sizes[i] == 0 || sizes[i] * 100 >= e.builtSize * (100 - kMinCompactionSavingPercent)) {
            ++counters.compactionsSkipped;
          } else {
            e.compactedSize = sizes[i];
          }
        }
      } else {
        failed(r, "BLAS compacted sizes");  // the BLASes stay uncompacted
      }
      c.vk.vkDestroyQueryPool(c.desc.device, b.compactedSizes, c.allocator());
    }
  }
  inFlightBatches = std::move(keep);
}

Status AccelerationStructureService::Impl::recordCompactions(VkCommandBuffer cmd, bool& recordedAny) {
  bool copied = false;
  Status status;  // a failed copy stays queued for the next call; the copies recorded before it still count
  for (uint32_t i = 1; i < entries.size(); ++i) {
    BlasEntry& e = entries[i];
    if (e.state != BlasState::Built || e.compactedSize == 0 || e.compacted) continue;
    Result<StorageAllocation> alloc = storage.allocate(e.compactedSize);
    if (!alloc) {
      status = alloc.error();
      break;
    }
    Result<VkAccelerationStructureKHR> as = createAs(VK_ACCELERATION_STRUCTURE_TYPE_BOTTOM_LEVEL_KHR,
                                                     storage.buffer(alloc->block), alloc->offset, e.compactedSize);
    if (!as) {
      storage.free(alloc.value());
      status = as.error();
      break;
    }
    VkCopyAccelerationStructureInfoKHR copy{VK_STRUCTURE_TYPE_COPY_ACCELERATION_STRUCTURE_INFO_KHR};
    copy.src = e.as;
    copy.dst = as.value();
    copy.mode = VK_COPY_ACCELERATION_STRUCTURE_MODE_COMPACT_KHR;
    c.vk.vkCmdCopyAccelerationStructureKHR(cmd, &copy);
    VkAccelerationStructureKHR old = e.as;
    StorageAllocation oldAlloc = e.storage;
    c.retire([this, old, oldAlloc] {
      c.vk.vkDestroyAccelerationStructureKHR(c.desc.device, old, c.allocator());
      storage.free(oldAlloc);
    });
    reservedBytes -= e.reserved;
    e.reserved = alloc->size;
    reservedBytes += e.reserved;
    e.as = as.value();
    e.storage = alloc.value();
    e.currentSize = e.compactedSize;
    VkAccelerationStructureDeviceAddressInfoKHR ai{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_DEVICE_ADDRESS_INFO_KHR};
    ai.accelerationStructure = e.as;
    e.address = c.vk.vkGetAccelerationStructureDeviceAddressKHR(c.desc.device, &ai);
    e.compacted = true;
    ++counters.blasCompacted;
    copied = true;
  }
  if (copied) {
    recordedAny = true;
    recordAsBarrier(c.vk, cmd, VK_PIPELINE_STAGE_ACCELERATION_STRUCTURE_BUILD_BIT_KHR);
  }
  return status;
}

Status AccelerationStructureService::Impl::recordBuildBatch(VkCommandBuffer cmd, std::vector<uint32_t>& batch,
                                                            VkDeviceSize scratchBytes, bool& recordedAny) {
  if (batch.empty()) return {};
  const VkDeviceSize align = scratchAlignment();
  // Everything that can fail comes first. A failure undoes it (nothing is recorded yet, so nothing is in use) and
  // puts the batch back at the front of the queue: the next call builds it.
  GpuBuffer transient;
  BuildBatch record;
  record.frame = c.frame;
  auto undo = [&](const Error& error) -> Status {
    for (uint32_t idx : batch) {
      BlasEntry& e = entries[idx];
      if (e.as) {
        c.vk.vkDestroyAccelerationStructureKHR(c.desc.device, e.as, c.allocator());
        storage.free(e.storage);
      }
      e.as = VK_NULL_HANDLE;
      e.storage = StorageAllocation{};
      e.address = 0;
      e.builtSize = e.currentSize = 0;
    }
    if (record.timestamps) freeTimestampPools.push_back(record.timestamps);
    destroyBuffer(ctx, transient);
    queue.insert(queue.begin(), batch.begin(), batch.end());
    return error;
  };

  // Scratch: the persistent buffer when the batch fits the budget, else transient scratch for this batch.
  VkDeviceAddress scratchBase = 0;
  if (scratchBytes > desc.scratchBudgetBytes) {
    Result<GpuBuffer> t = createBuffer(ctx, scratchBytes + align,
                                       VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | VK_BUFFER_USAGE_SHADER_DEVICE_ADDRESS_BIT,
                                       MemoryLocation::DeviceLocal, MemoryCategory::Scratch, "oversized BLAS scratch");
    if (!t) return undo(t.error());
    transient = t.value();
    scratchBase = alignUp(transient.address, align);
  } else {
    if (!scratch.valid()) {
      Result<GpuBuffer> t = createBuffer(ctx, desc.scratchBudgetBytes + align,
                                         VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | VK_BUFFER_USAGE_SHADER_DEVICE_ADDRESS_BIT,
                                         MemoryLocation::DeviceLocal, MemoryCategory::Scratch, "BLAS build scratch");
      if (!t) return undo(t.error());
      scratch = t.value();
    }
    scratchBase = alignUp(scratch.address, align);
  }
  for (uint32_t idx : batch) {
    BlasEntry& e = entries[idx];
    Result<StorageAllocation> alloc = storage.allocate(e.sizes.accelerationStructureSize);
    if (!alloc) return undo(alloc.error());
    Result<VkAccelerationStructureKHR> as = createAs(VK_ACCELERATION_STRUCTURE_TYPE_BOTTOM_LEVEL_KHR,
                                                     storage.buffer(alloc->block), alloc->offset,
                                                     e.sizes.accelerationStructureSize);
    if (!as) {
      storage.free(alloc.value());
      return undo(as.error());
    }
    e.as = as.value();
    e.storage = alloc.value();
  }
  if (!desc.disableTimestamps && c.info.timestampsSupported) {
    Result<VkQueryPool> pool = takeTimestampPool(freeTimestampPools, "build timestamps");
    if (!pool) return undo(pool.error());
    record.timestamps = pool.value();
  }
  for (uint32_t idx : batch) {
    if (blasFlags(entries[idx]) & VK_BUILD_ACCELERATION_STRUCTURE_ALLOW_COMPACTION_BIT_KHR) {
      record.compactEntries.push_back(idx);
      record.compactGenerations.push_back(entries[idx].generation);
    }
  }
  if (!record.compactEntries.empty()) {
    VkQueryPoolCreateInfo qi{VK_STRUCTURE_TYPE_QUERY_POOL_CREATE_INFO};
    qi.queryType = VK_QUERY_TYPE_ACCELERATION_STRUCTURE_COMPACTED_SIZE_KHR;
    qi.queryCount = static_cast<uint32_t>(record.compactEntries.size());
    VkQueryPool pool = VK_NULL_HANDLE;
    VkResult r = c.vk.vkCreateQueryPool(c.desc.device, &qi, c.allocator(), &pool);
    if (r != VK_SUCCESS) return undo(vulkanError(r, "vkCreateQueryPool (compacted sizes)"));
    record.compactedSizes = pool;
  }

  std::vector<VkAccelerationStructureGeometryKHR> geometries(batch.size());
  std::vector<VkAccelerationStructureBuildRangeInfoKHR> ranges(batch.size());
  std::vector<const VkAccelerationStructureBuildRangeInfoKHR*> rangePtrs(batch.size());
  std::vector<VkAccelerationStructureBuildGeometryInfoKHR> infos(batch.size());
  VkDeviceSize offset = 0;
  for (size_t i = 0; i < batch.size(); ++i) {
    BlasEntry& e = entries[batch[i]];
    VkAccelerationStructureDeviceAddressInfoKHR ai{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_DEVICE_ADDRESS_INFO_KHR};
    ai.accelerationStructure = e.as;
    e.address = c.vk.vkGetAccelerationStructureDeviceAddressKHR(c.desc.device, &ai);
    e.builtSize = e.sizes.accelerationStructureSize;
    e.currentSize = e.builtSize;
    buildGeometry(e, geometries[i], ranges[i]);
    rangePtrs[i] = &ranges[i];
    VkAccelerationStructureBuildGeometryInfoKHR& info = infos[i];
    info = VkAccelerationStructureBuildGeometryInfoKHR{
        VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_BUILD_GEOMETRY_INFO_KHR};
    info.type = VK_ACCELERATION_STRUCTURE_TYPE_BOTTOM_LEVEL_KHR;
    info.flags = blasFlags(e);
    info.mode = VK_BUILD_ACCELERATION_STRUCTURE_MODE_BUILD_KHR;
    info.dstAccelerationStructure = e.as;
    info.geometryCount = 1;
    info.pGeometries = &geometries[i];
    info.scratchData.deviceAddress = scratchBase + offset;
    offset += alignUp(e.sizes.buildScratchSize, align);
    record.triangles += e.mesh.desc.triangleCount;
    e.compactionPending = (info.flags & VK_BUILD_ACCELERATION_STRUCTURE_ALLOW_COMPACTION_BIT_KHR) != 0;
  }
  record.builds = static_cast<uint32_t>(batch.size());

  if (record.timestamps) c.vk.vkCmdResetQueryPool(cmd, record.timestamps, 0, 2);
  if (record.compactedSizes) {
    c.vk.vkCmdResetQueryPool(cmd, record.compactedSizes, 0, static_cast<uint32_t>(record.compactEntries.size()));
  }
  // Orders this batch after earlier users of the scratch memory and the storage (earlier batches, earlier
  // frames on the same queue).
  recordAsBarrier(c.vk, cmd, VK_PIPELINE_STAGE_ACCELERATION_STRUCTURE_BUILD_BIT_KHR);
  if (record.timestamps) {
    c.vk.vkCmdWriteTimestamp(cmd, VK_PIPELINE_STAGE_ALL_COMMANDS_BIT, record.timestamps, 0);
  }
  c.vk.vkCmdBuildAccelerationStructuresKHR(cmd, static_cast<uint32_t>(infos.size()), infos.data(), rangePtrs.data());
  if (record.timestamps) {
    c.vk.vkCmdWriteTimestamp(cmd, VK_PIPELINE_STAGE_ALL_COMMANDS_BIT, record.timestamps, 1);
  }
  recordAsBarrier(
      c.vk, cmd, VK_PIPELINE_STAGE_ACCELERATION_STRUCTURE_BUILD_BIT_KHR | VK_PIPELINE_STAGE_RAY_TRACING_SHADER_BIT_KHR);
  if (record.compactedSizes) {
    std::vector<VkAccelerationStructureKHR> handles;
    for (uint32_t idx : record.compactEntries) handles.push_back(entries[idx].as);
    c.vk.vkCmdWriteAccelerationStructuresPropertiesKHR(cmd, static_cast<uint32_t>(handles.size()), handles.data(),
                                                       VK_QUERY_TYPE_ACCELERATION_STRUCTURE_COMPACTED_SIZE_KHR,
                                                       record.compactedSizes, 0);
  }
  for (uint32_t idx : batch) entries[idx].state = BlasState::Built;
  if (transient.valid()) retireBuffer(ctx, transient);
  inFlightBatches.push_back(std::move(record));
  recordedAny = true;
  return {};
}

Result<uint32_t> AccelerationStructureService::recordPendingWork(VkCommandBuffer cmd) {
  Impl& s = *impl_;
  std::lock_guard<std::mutex> lock(s.mutex);
  s.handOnDeferredRetires();
  if (!cmd) return Error{ErrorCode::InvalidArgument, VK_SUCCESS, "recordPendingWork: cmd is VK_NULL_HANDLE"};
  s.resolveBatches();
  if (!s.queryError) return std::exchange(s.queryError, Status()).error();
  bool recordedAny = false;
  if (Status st = s.recordCompactions(cmd, recordedAny); !st) return st.error();

  const VkDeviceSize align = s.scratchAlignment();
  uint64_t trianglesThisCall = 0;
  // Deforming meshes first (in-frame modes; the async modes submit them in submitDynamicWork): refits are
  // cheap and their TLAS instances are already live.
  if (!s.async) {
    if (Status st = s.recordDynamicWork(cmd, trianglesThisCall, recordedAny); !st) return st.error();
  }

  const uint64_t triangleCap = s.desc.maxBuildTrianglesPerCall;
  std::vector<uint32_t> batch;
  VkDeviceSize batchScratch = 0;
  while (!s.queue.empty()) {
    uint32_t index = s.queue.front();
    BlasEntry& e = s.entries[index];
    VkDeviceSize need = alignUp(e.sizes.buildScratchSize, align);
    if (triangleCap && trianglesThisCall > 0 && trianglesThisCall + e.mesh.desc.triangleCount > triangleCap) break;
    if (!batch.empty() && batchScratch + need > s.desc.scratchBudgetBytes) {
      if (Status st = s.recordBuildBatch(cmd, batch, batchScratch, recordedAny); !st) return st.error();
      batch.clear();
      batchScratch = 0;
    }
    s.queue.pop_front();
    batch.push_back(index);
    batchScratch += need;
    trianglesThisCall += e.mesh.desc.triangleCount;
  }
  if (Status st = s.recordBuildBatch(cmd, batch, batchScratch, recordedAny); !st) return st.error();
  (void)recordedAny;
  uint32_t queued = static_cast<uint32_t>(s.queue.size());
  for (uint32_t i = 1; i < s.entries.size(); ++i) {
    const BlasEntry& e = s.entries[i];
    queued += e.state == BlasState::Queued && e.mesh.desc.role == MeshRole::Dynamic ? 1u : 0u;
  }
  return queued;
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
  if (e.state != BlasState::Built) {
    return Error{ErrorCode::NotReady, VK_SUCCESS, "blasAddress: the mesh's BLAS build has not been recorded yet"};
  }
  return e.address;
}

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
  out.blasCount = out.blasQueued = 0;
  out.triangles = out.blasBytes = out.blasBytesBeforeCompaction = out.dynamicBlasBytes = 0;
  for (uint32_t i = 1; i < s.entries.size(); ++i) {
    const BlasEntry& e = s.entries[i];
    if (e.state == BlasState::Free) continue;
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
