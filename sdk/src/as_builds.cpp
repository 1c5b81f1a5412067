// Batched BLAS builds of the acceleration-structure service: recordPendingWork packs queued builds into batches
// whose scratch fits the budget (and whose triangles fit the per-call cap) and records them.
#include <raybridge/acceleration_structures.h>

#include <string>
#include <utility>
#include <vector>

#include "align_up.h"
#include "as_service_impl.h"

namespace rb {

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

}  // namespace rb
