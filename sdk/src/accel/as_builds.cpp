// Batched BLAS builds of the acceleration-structure service: recordPendingWork packs queued builds into batches
// whose scratch fits the budget (and whose triangles fit the per-call cap) and records them; a mesh whose BLAS
// cannot be created fails alone (MeshState::Failed) and is retried by the next call.
#include <raybridge/acceleration_structures.h>

#include <string>
#include <utility>
#include <vector>

#include "align_up.h"
#include "as_service_impl.h"

namespace rb {

namespace {

using Impl = AccelerationStructureService::Impl;

// The scratch a batch's builds use: the shared buffer (grown to the batch) when the batch fits the budget, else
// `transient`, made for this batch.
Result<VkDeviceAddress> acquireBatchScratch(Impl& s, VkDeviceSize scratchBytes, GpuBuffer& transient) {
  const VkDeviceSize align = s.scratchAlignment();
  const VkBufferUsageFlags usage = VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | VK_BUFFER_USAGE_SHADER_DEVICE_ADDRESS_BIT;
  if (scratchBytes > s.desc.scratchBudgetBytes) {
    Result<GpuBuffer> t = createBuffer(s.ctx, scratchBytes + align, usage, MemoryLocation::DeviceLocal,
                                       MemoryCategory::Scratch, "oversized BLAS scratch");
    if (!t) return t.error();
    transient = t.value();
    return alignUp(transient.address, align);
  }
  return s.sharedScratch(scratchBytes);
}

// Creates the storage and the acceleration structure of each mesh of the batch. One whose objects cannot be
// created is marked Failed and leaves the batch (the first such error goes to `meshFailure`): the others build.
void createBatchBlases(Impl& s, std::vector<uint32_t>& batch, Status& meshFailure) {
  std::vector<uint32_t> created;
  for (uint32_t idx : batch) {
    BlasEntry& e = s.entries[idx];
    Result<StorageAllocation> alloc = s.storage.allocate(e.sizes.accelerationStructureSize);
    Result<VkAccelerationStructureKHR> as = alloc ? s.createAs(VK_ACCELERATION_STRUCTURE_TYPE_BOTTOM_LEVEL_KHR,
                                                               s.storage.buffer(alloc->block), alloc->offset,
                                                               e.sizes.accelerationStructureSize)
                                                  : Result<VkAccelerationStructureKHR>(alloc.error());
    if (!as) {
      if (alloc) s.storage.free(alloc.value());
      Error error = as.error();
      error.message = "building the BLAS of the " + s.meshName(e) + ": " + error.message +
                      "; it is MeshState::Failed and the next recordPendingWork retries it (evictMesh stops the "
                      "retries, releaseMesh ends them)";
      if (meshFailure) meshFailure = error;
      s.markBuildFailed(idx, std::move(error));
      continue;
    }
    e.as = as.value();
    e.storage = alloc.value();
    created.push_back(idx);
  }
  batch = std::move(created);
}

// The batch's queries: timestamps around it, and the compacted sizes of the BLASes built for compaction.
Status createBatchQueries(Impl& s, const std::vector<uint32_t>& batch, BuildBatch& record) {
  Context::Impl& c = s.c;
  if (!s.desc.disableTimestamps && c.info.timestampsSupported) {
    Result<VkQueryPool> pool = s.takeTimestampPool(s.freeTimestampPools, "build timestamps");
    if (!pool) return pool.error();
    record.timestamps = pool.value();
  }
  for (uint32_t idx : batch) {
    if (s.blasFlags(s.entries[idx]) & VK_BUILD_ACCELERATION_STRUCTURE_ALLOW_COMPACTION_BIT_KHR) {
      record.compactEntries.push_back(idx);
      record.compactGenerations.push_back(s.entries[idx].generation);
    }
  }
  if (!record.compactEntries.empty()) {
    VkQueryPoolCreateInfo qi{VK_STRUCTURE_TYPE_QUERY_POOL_CREATE_INFO};
    qi.queryType = VK_QUERY_TYPE_ACCELERATION_STRUCTURE_COMPACTED_SIZE_KHR;
    qi.queryCount = static_cast<uint32_t>(record.compactEntries.size());
    VkQueryPool pool = VK_NULL_HANDLE;
    VkResult r = c.vk.vkCreateQueryPool(c.desc.device, &qi, c.allocator(), &pool);
    if (r != VK_SUCCESS) return vulkanError(r, "vkCreateQueryPool (compacted sizes)");
    record.compactedSizes = pool;
  }
  return {};
}

// The build descriptions of a batch, packed into its scratch.
struct BatchBuildInfos {
  std::vector<VkAccelerationStructureGeometryKHR> geometries;
  std::vector<VkAccelerationStructureBuildRangeInfoKHR> ranges;
  std::vector<const VkAccelerationStructureBuildRangeInfoKHR*> rangePtrs;
  std::vector<VkAccelerationStructureBuildGeometryInfoKHR> infos;
};

void fillBatchBuildInfos(Impl& s, const std::vector<uint32_t>& batch, VkDeviceAddress scratchBase, BatchBuildInfos& b,
                         BuildBatch& record) {
  Context::Impl& c = s.c;
  const VkDeviceSize align = s.scratchAlignment();
  b.geometries.resize(batch.size());
  b.ranges.resize(batch.size());
  b.rangePtrs.resize(batch.size());
  b.infos.resize(batch.size());
  VkDeviceSize offset = 0;
  for (size_t i = 0; i < batch.size(); ++i) {
    BlasEntry& e = s.entries[batch[i]];
    VkAccelerationStructureDeviceAddressInfoKHR ai{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_DEVICE_ADDRESS_INFO_KHR};
    ai.accelerationStructure = e.as;
    e.address = c.vk.vkGetAccelerationStructureDeviceAddressKHR(c.desc.device, &ai);
    e.builtSize = e.sizes.accelerationStructureSize;
    e.currentSize = e.builtSize;
    s.buildGeometry(e, b.geometries[i], b.ranges[i]);
    b.rangePtrs[i] = &b.ranges[i];
    VkAccelerationStructureBuildGeometryInfoKHR& info = b.infos[i];
    info = VkAccelerationStructureBuildGeometryInfoKHR{
        VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_BUILD_GEOMETRY_INFO_KHR};
    info.type = VK_ACCELERATION_STRUCTURE_TYPE_BOTTOM_LEVEL_KHR;
    info.flags = s.blasFlags(e);
    info.mode = VK_BUILD_ACCELERATION_STRUCTURE_MODE_BUILD_KHR;
    info.dstAccelerationStructure = e.as;
    info.geometryCount = 1;
    info.pGeometries = &b.geometries[i];
    info.scratchData.deviceAddress = scratchBase + offset;
    offset += alignUp(e.sizes.buildScratchSize, align);
    record.triangles += e.mesh.desc.triangleCount;
    e.compactionPending = (info.flags & VK_BUILD_ACCELERATION_STRUCTURE_ALLOW_COMPACTION_BIT_KHR) != 0;
  }
  record.builds = static_cast<uint32_t>(batch.size());
}

// The builds between barriers, timed, followed by the compacted-size queries.
void recordBatchCommands(Impl& s, VkCommandBuffer cmd, const BatchBuildInfos& b, const BuildBatch& record) {
  Context::Impl& c = s.c;
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
  c.vk.vkCmdBuildAccelerationStructuresKHR(cmd, static_cast<uint32_t>(b.infos.size()), b.infos.data(),
                                           b.rangePtrs.data());
  if (record.timestamps) {
    c.vk.vkCmdWriteTimestamp(cmd, VK_PIPELINE_STAGE_ALL_COMMANDS_BIT, record.timestamps, 1);
  }
  recordAsBarrier(
      c.vk, cmd, VK_PIPELINE_STAGE_ACCELERATION_STRUCTURE_BUILD_BIT_KHR | VK_PIPELINE_STAGE_RAY_TRACING_SHADER_BIT_KHR);
  if (record.compactedSizes) {
    std::vector<VkAccelerationStructureKHR> handles;
    for (uint32_t idx : record.compactEntries) handles.push_back(s.entries[idx].as);
    c.vk.vkCmdWriteAccelerationStructuresPropertiesKHR(cmd, static_cast<uint32_t>(handles.size()), handles.data(),
                                                       VK_QUERY_TYPE_ACCELERATION_STRUCTURE_COMPACTED_SIZE_KHR,
                                                       record.compactedSizes, 0);
  }
}

}  // namespace

Status AccelerationStructureService::Impl::recordBuildBatch(VkCommandBuffer cmd, std::vector<uint32_t>& batch,
                                                            VkDeviceSize scratchBytes, bool& recordedAny,
                                                            Status& meshFailure) {
  if (batch.empty()) return {};
  // Everything that can fail comes first. A failure of the batch's own objects undoes it (nothing is recorded yet,
  // so nothing is in use) and puts the batch back at the front of the queue: the next call builds it.
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

  Result<VkDeviceAddress> scratchBase = acquireBatchScratch(*this, scratchBytes, transient);
  if (!scratchBase) return undo(scratchBase.error());
  createBatchBlases(*this, batch, meshFailure);
  if (batch.empty()) {
    destroyBuffer(ctx, transient);  // every mesh of the batch failed: nothing uses it
    return {};
  }
  if (Status st = createBatchQueries(*this, batch, record); !st) return undo(st.error());

  BatchBuildInfos infos;
  fillBatchBuildInfos(*this, batch, scratchBase.value(), infos, record);
  recordBatchCommands(*this, cmd, infos, record);
  for (uint32_t idx : batch) {
    entries[idx].state = BlasState::Built;
    entries[idx].failure = Error{};  // a retry that worked
  }
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
  s.trimReleasedCache();  // what releaseMesh could not free because a frame in flight read it
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

  // Failed builds go after those queued before them: a mesh that keeps failing never holds up the others.
  Status meshFailure;
  s.retryFailedBuilds(meshFailure);
  const uint64_t triangleCap = s.desc.maxBuildTrianglesPerCall;
  std::vector<uint32_t> batch;
  VkDeviceSize batchScratch = 0;
  while (!s.queue.empty()) {
    uint32_t index = s.queue.front();
    BlasEntry& e = s.entries[index];
    VkDeviceSize need = alignUp(e.sizes.buildScratchSize, align);
    if (triangleCap && trianglesThisCall > 0 && trianglesThisCall + e.mesh.desc.triangleCount > triangleCap) break;
    if (!batch.empty() && batchScratch + need > s.desc.scratchBudgetBytes) {
      if (Status st = s.recordBuildBatch(cmd, batch, batchScratch, recordedAny, meshFailure); !st) return st.error();
      batch.clear();
      batchScratch = 0;
    }
    s.queue.pop_front();
    batch.push_back(index);
    batchScratch += need;
    trianglesThisCall += e.mesh.desc.triangleCount;
  }
  if (Status st = s.recordBuildBatch(cmd, batch, batchScratch, recordedAny, meshFailure); !st) return st.error();
  (void)recordedAny;
  s.trimSharedScratch();
  if (!meshFailure) return meshFailure.error();
  uint32_t queued = static_cast<uint32_t>(s.queue.size());
  for (uint32_t i = 1; i < s.entries.size(); ++i) {
    const BlasEntry& e = s.entries[i];
    queued += e.state == BlasState::Queued && e.mesh.desc.role == MeshRole::Dynamic ? 1u : 0u;
  }
  return queued;
}

}  // namespace rb
