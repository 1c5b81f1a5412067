// The acceleration-structure service's lifetime (create, destruction, deferred retires) and the helpers its parts
// share: handle lookup, build geometry, flags and sizes, acceleration-structure objects, timestamp pools. The parts:
// as_registration.cpp (registration, dedup, budget), as_builds.cpp (batched builds), as_compaction.cpp (build
// queries, compaction), as_mesh_state.cpp (states, eviction), as_stats.cpp, dynamic_*.cpp, tlas_builder.cpp.
#include <raybridge/acceleration_structures.h>

#include <algorithm>
#include <string>
#include <utility>

#include "align_up.h"
#include "as_service_impl.h"

namespace rb {

namespace {

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
  releasedCacheCap = desc.disableReleasedCache      ? 0
                     : desc.releasedCacheBytes != 0 ? desc.releasedCacheBytes
                                                    : kDefaultReleasedCacheBytes;
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

Result<VkDeviceAddress> AccelerationStructureService::Impl::growScratch(GpuBuffer& buffer, VkDeviceSize need,
                                                                        VkDeviceSize cap, const char* what) {
  const VkDeviceSize align = scratchAlignment();
  if (!buffer.valid() || buffer.size < need + align) {
    const VkDeviceSize bytes = buffer.valid() ? std::max(need, std::min(2 * (buffer.size - align), cap)) : need;
    // Earlier builds of this command buffer, or of frames (or async submissions) in flight, may still use it.
    retireBufferAfterAsync(buffer);
    Result<GpuBuffer> t = createBuffer(ctx, bytes + align,
                                       VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | VK_BUFFER_USAGE_SHADER_DEVICE_ADDRESS_BIT,
                                       MemoryLocation::DeviceLocal, MemoryCategory::Scratch, what);
    if (!t) return t.error();
    buffer = t.value();
  }
  return alignUp(buffer.address, align);
}

Result<VkDeviceAddress> AccelerationStructureService::Impl::sharedScratch(VkDeviceSize need) {
  scratchNeedInWindow = std::max(scratchNeedInWindow, need);
  return growScratch(scratch, need, desc.scratchBudgetBytes, "BLAS build scratch");
}

void AccelerationStructureService::Impl::trimSharedScratch() {
  if (++scratchWindowCalls < kScratchWindowCalls) return;
  if (scratch.valid() && scratchNeedInWindow * 4 <= scratch.size - scratchAlignment()) retireBufferAfterAsync(scratch);
  scratchWindowCalls = 0;
  scratchNeedInWindow = 0;
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

}  // namespace rb
