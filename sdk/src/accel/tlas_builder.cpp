// The TLAS side of the acceleration-structure service: one TLAS per frame slot, rebuilt or refit every frame
// from the engine's instance list.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <string>

#include "align_up.h"
#include "as_service_impl.h"
#include "content_hash.h"
#include "memory_barrier.h"

namespace rb {

namespace {

using Impl = AccelerationStructureService::Impl;

// Grows `buffer` to hold `bytes`, retiring the old one (a frame in flight may still read it).
Status ensureBuffer(Context& ctx, GpuBuffer& buffer, VkDeviceSize bytes, VkBufferUsageFlags usage,
                    MemoryLocation location, const char* what) {
  if (buffer.valid() && buffer.size >= bytes) return {};
  retireBuffer(ctx, buffer);
  Result<GpuBuffer> b = createBuffer(ctx, bytes, usage, location, MemoryCategory::Tlas, what);
  if (!b) return b.error();
  buffer = b.value();
  return {};
}

// Whether the memory host-visible buffers get (gpu_memory.cpp: the first HOST_VISIBLE | HOST_COHERENT type) is
// also device-local: an integrated GPU, a CPU driver, or a resizable BAR heap listed first.
bool hostMemoryIsDeviceLocal(const Context::Impl& c) {
  const VkMemoryPropertyFlags hostFlags = VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT | VK_MEMORY_PROPERTY_HOST_COHERENT_BIT;
  const int32_t type = c.findMemoryType(~0u, hostFlags, hostFlags);
  return type >= 0 && (c.memoryProperties.memoryTypes[type].propertyFlags & VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT);
}


Status validateTlasOptions(const Context::Impl& c, size_t instanceCount, const TlasBuildOptions& options) {
  if (options.mode > TlasBuildMode::UpdateIfPossible || options.instanceUpload > TlasInstanceUpload::CopyToDevice ||
      options.preference > TlasBuildPreference::FastBuild) {
    return Error{ErrorCode::InvalidArgument, VK_SUCCESS,
                 "recordTlasBuild: options.mode (" + std::to_string(int(options.mode)) + "), options.instanceUpload (" +
                     std::to_string(int(options.instanceUpload)) + ") or options.preference (" +
                     std::to_string(int(options.preference)) + ") is not one of its enum's values"};
  }
  if (options.maxAreaGrowth != 0.0f && !(options.maxAreaGrowth > 1.0f && std::isfinite(options.maxAreaGrowth))) {
    return Error{ErrorCode::InvalidArgument, VK_SUCCESS,
                 "recordTlasBuild: options.maxAreaGrowth is " + std::to_string(options.maxAreaGrowth) +
                     "; use 0 for kDefaultTlasMaxAreaGrowth or a finite value above 1 (the area multiple that "
                     "triggers a rebuild)"};
  }
  if (instanceCount > c.info.maxInstanceCount) {
    return Error{ErrorCode::InvalidArgument, VK_SUCCESS,
                 "recordTlasBuild: " + std::to_string(instanceCount) + " instances exceed the device limit of " +
                     std::to_string(c.info.maxInstanceCount)};
  }
  return {};
}

// The slot's host-visible instance buffer (grown geometrically so a growing scene does not reallocate every frame),
// its device-local copy when the build reads one, and the shading records with their copy.
Status prepareInstanceBuffers(Impl& s, TlasSlot& slot, uint32_t count, const TlasBuildOptions& options,
                              bool copyInstances) {
  if (count > slot.instanceCapacity || !slot.instances.valid()) {
    uint32_t capacity = std::max<uint32_t>({count, slot.instanceCapacity + slot.instanceCapacity / 2, 64u});
    retireBuffer(s.ctx, slot.instances);
    Status st = ensureBuffer(s.ctx, slot.instances, VkDeviceSize(capacity) * sizeof(VkAccelerationStructureInstanceKHR),
                             VK_BUFFER_USAGE_ACCELERATION_STRUCTURE_BUILD_INPUT_READ_ONLY_BIT_KHR |
                                 VK_BUFFER_USAGE_SHADER_DEVICE_ADDRESS_BIT | VK_BUFFER_USAGE_TRANSFER_SRC_BIT,
                             MemoryLocation::HostVisible, "TLAS instance buffer");
    if (!st) return st;
    slot.instanceCapacity = capacity;
  }
  if (copyInstances) {
    const VkDeviceSize need = VkDeviceSize(slot.instanceCapacity) * sizeof(VkAccelerationStructureInstanceKHR);
    Status st = ensureBuffer(s.ctx, slot.deviceInstances, need,
                             VK_BUFFER_USAGE_ACCELERATION_STRUCTURE_BUILD_INPUT_READ_ONLY_BIT_KHR |
                                 VK_BUFFER_USAGE_SHADER_DEVICE_ADDRESS_BIT | VK_BUFFER_USAGE_TRANSFER_DST_BIT,
                             MemoryLocation::DeviceLocal, "TLAS device instance buffer");
    if (!st) return st;
  } else if (slot.deviceInstances.valid()) {
    retireBuffer(s.ctx, slot.deviceInstances);  // not read any more: held memory nothing uses
  }

  if (options.writeShadingRecords) {
    VkDeviceSize need = VkDeviceSize(std::max(slot.instanceCapacity, 1u)) * sizeof(ShadingRecord);
    if (slot.shading.size < need) {
      retireBuffer(s.ctx, slot.shading);
      Status st = ensureBuffer(s.ctx, slot.shading, need,
                               VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | VK_BUFFER_USAGE_TRANSFER_SRC_BIT,
                               MemoryLocation::HostVisible, "TLAS shading records");
      if (!st) return st;
    }
    if (copyInstances) {
      // TRANSFER_SRC: the engine (or a test) may copy TlasInfo::shadingRecords, whichever buffer it is.
      Status st = ensureBuffer(s.ctx, slot.deviceShading, need,
                               VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | VK_BUFFER_USAGE_TRANSFER_DST_BIT |
                                   VK_BUFFER_USAGE_TRANSFER_SRC_BIT,
                               MemoryLocation::DeviceLocal, "TLAS device shading records");
      if (!st) return st;
    }
  }
  if ((!copyInstances || !options.writeShadingRecords) && slot.deviceShading.valid())
    retireBuffer(s.ctx, slot.deviceShading);
  return {};
}

// Every handle and field checked before anything is written, so a bad list leaves the previous state untouched.
Status validateInstances(const Impl& s, std::span<const Instance> instances) {
  for (uint32_t i = 0; i < instances.size(); ++i) {
    const Instance& in = instances[i];
    const MeshHandle h = in.mesh;
    if (h.isNull() || h.index >= s.registrations.size() || s.registrations[h.index].generation != h.generation ||
        !s.registrations[h.index].live) {
      return Error{ErrorCode::StaleHandle, VK_SUCCESS,
                   "recordTlasBuild: instances[" + std::to_string(i) + "] refers to " +
                       (h.isNull() ? std::string("the null mesh handle")
                                   : "mesh handle {index " + std::to_string(h.index) + ", generation " +
                                         std::to_string(h.generation) +
                                         "}, which was released, evicted or never "
                                         "registered")};
    }
    if (in.customIndex > 0xFFFFFFu) {
      return Error{ErrorCode::InvalidArgument, VK_SUCCESS,
                   "recordTlasBuild: instances[" + std::to_string(i) + "].customIndex " +
                       std::to_string(in.customIndex) + " does not fit in 24 bits"};
    }
    if (in.sbtRecordOffset > 0xFFFFFFu) {
      return Error{ErrorCode::InvalidArgument, VK_SUCCESS,
                   "recordTlasBuild: instances[" + std::to_string(i) + "].sbtRecordOffset does not fit in 24 bits"};
    }
  }
  return {};
}

// This registration's own buffers and attributes, and the instance's material.
ShadingRecord shadingRecordFor(const MeshDesc& m, uint32_t material) {
  ShadingRecord r{};
  r.positions = m.vertexAddress;
  r.indices = m.indexAddress;
  r.normals = m.normalAddress;
  r.texcoords = m.texcoordAddress;
  r.positionStride = m.vertexStride;
  r.normalStride = m.normalStride;
  r.texcoordStride = m.texcoordStride;
  r.indexType = m.indexType == IndexType::Uint32 ? 0u : m.indexType == IndexType::Uint16 ? 1u : 2u;
  r.material = material;
  r.positionFormat = static_cast<uint32_t>(m.vertexFormat);
  return r;
}

VkAccelerationStructureInstanceKHR vulkanInstance(const Instance& in, const TlasBuildOptions& options, bool rebase,
                                                  VkDeviceAddress blas) {
  VkAccelerationStructureInstanceKHR inst;
  std::memcpy(&inst.transform, in.transform, sizeof(inst.transform));
  if (rebase) {
    for (int row = 0; row < 3; ++row) {
      inst.transform.matrix[row][3] = static_cast<float>(static_cast<double>(in.transform[row * 4 + 3]) -
                                                         options.originOffset[row]);
    }
  }
  inst.instanceCustomIndex = in.customIndex;
  inst.mask = in.mask;
  inst.instanceShaderBindingTableRecordOffset = in.sbtRecordOffset;
  inst.flags = in.flags;
  inst.accelerationStructureReference = blas;
  return inst;
}

// What writeInstances wrote into the slot's buffers.
struct WrittenInstances {
  uint32_t written = 0, skipped = 0, failed = 0, stale = 0, nonOpaque = 0;
  uint64_t signature = 0;  // hash of the BLAS addresses in order (TlasSlot::blasSignature)
};

// The BLAS address an instance of `e` references this frame (0: none to reference yet), marking the copy used.
VkDeviceAddress blasForInstance(Impl& s, BlasEntry& e, uint32_t& stale) {
  if (e.state != BlasState::Built) return 0;
  if (e.mesh.desc.role != MeshRole::Dynamic) return e.address;
  // The copy this mode traces (the previous frame's pose when one frame late).
  const int32_t k = s.tlasCopy(e);
  if (k < 0) return 0;
  BlasCopy& copy = e.dyn.copies[k];
  copy.used = true;
  copy.lastUsedFrame = s.c.frame;
  if (copy.pose < e.dyn.pose) ++stale;
  return copy.address;
}

// An evicted mesh a TLAS references is built again: Queued, or Failed when the budget cannot hold it.
void requeueForTlas(Impl& s, uint32_t index) {
  const std::string what = "recordTlasBuild: re-queuing the build of the evicted " + s.meshName(s.entries[index]);
  if (Status st = s.requeueEvicted(index, what); !st) {
    Error e = st.error();
    e.message += "; until then TLAS builds leave it out (TlasInfo::failedInstances) and recordPendingWork retries it";
    s.markBuildFailed(index, std::move(e));
  }
}

// Writes the instances of built meshes (and their shading records) into the slot's host-visible buffers, the
// transforms for the Adaptive measure into s.tlasTransforms, and marks the BLASes used by TLAS `serial`.
WrittenInstances writeInstances(Impl& s, TlasSlot& slot, std::span<const Instance> instances,
                                const TlasBuildOptions& options, uint64_t serial) {
  WrittenInstances w;
  auto* out = static_cast<VkAccelerationStructureInstanceKHR*>(slot.instances.mapped);
  auto* records = options.writeShadingRecords ? static_cast<ShadingRecord*>(slot.shading.mapped) : nullptr;
  const bool adaptive = options.mode == TlasBuildMode::Adaptive;
  if (adaptive) s.tlasTransforms.clear();
  const bool rebase = options.originOffset[0] != 0.0 || options.originOffset[1] != 0.0 ||
                      options.originOffset[2] != 0.0;
  for (const Instance& in : instances) {
    const Registration& reg = s.registrations[in.mesh.index];
    BlasEntry& e = s.entries[reg.blas];
    if (e.state == BlasState::Evicted) requeueForTlas(s, reg.blas);
    if (e.state == BlasState::Failed) {
      ++w.failed;
      continue;
    }
    const VkDeviceAddress blas = blasForInstance(s, e, w.stale);
    if (blas == 0) {
      ++w.skipped;
      continue;
    }
    const VkAccelerationStructureInstanceKHR inst = vulkanInstance(in, options, rebase, blas);
    if (adaptive) {
      const float* m = &inst.transform.matrix[0][0];  // row-major 3x4, contiguous
      s.tlasTransforms.insert(s.tlasTransforms.end(), m, m + TlasMotionMeasure::kFloatsPerInstance);
    }
    if (records) records[w.written] = shadingRecordFor(reg.mesh.desc, in.material);
    const bool forcedOpaque = (in.flags & VK_GEOMETRY_INSTANCE_FORCE_OPAQUE_BIT_KHR) != 0;
    const bool forcedNonOpaque = (in.flags & VK_GEOMETRY_INSTANCE_FORCE_NO_OPAQUE_BIT_KHR) != 0;
    if (forcedNonOpaque || (reg.mesh.desc.nonOpaque && !forcedOpaque)) ++w.nonOpaque;
    out[w.written++] = inst;
    e.lastUsedFrame = s.c.frame;
    e.lastTlasSerial = serial;
    w.signature = hashCombine(w.signature, blas);
  }
  return w;
}

// Tells eviction (which may run on a registration thread, away from c.frame) when this frame is done.
void retireFrameMarker(Impl& s) {
  s.c.retire([done = s.framesDoneBelow, frame = s.c.frame] {
    uint64_t seen = done->load();
    while (seen < frame + 1 && !done->compare_exchange_weak(seen, frame + 1)) {
    }
  });
}

// The TLAS this build refits (nullptr: a full build). A refit must start from an intact TLAS built for the same
// instances with the same flags (a changed build preference rebuilds): the one recorded last, in whichever slot,
// with the same BLASes in the same order. Adaptive: a valid refit still rebuilds when the instances drifted apart
// or after maxRefits refits; `growth` is then the measure.
const TlasSlot* chooseRefitSource(Impl& s, const TlasBuildOptions& options, VkBuildAccelerationStructureFlagsKHR flags,
                                  const WrittenInstances& w, uint64_t serial, float& growth) {
  const bool wantUpdate = options.mode != TlasBuildMode::Rebuild;
  const TlasSlot* source = nullptr;
  if (wantUpdate && s.lastTlasSlot < s.tlasSlots.size()) {
    const TlasSlot& prev = s.tlasSlots[s.lastTlasSlot];
    if (prev.tlas && prev.allowsUpdate && prev.builtFlags == flags && prev.builtInstanceCount == w.written &&
        prev.blasSignature == w.signature) {
      source = &prev;
    }
  }
  const bool adaptive = options.mode == TlasBuildMode::Adaptive;
  // The measure describes the chain only if the previous TLAS was built in this mode too.
  if (adaptive && source && s.tlasMotionSerial + 1 != serial) source = nullptr;
  if (adaptive && source) {
    const uint32_t maxRefits = options.maxRefits ? options.maxRefits : kDefaultTlasMaxRefits;
    const float maxGrowth = options.maxAreaGrowth != 0.0f ? options.maxAreaGrowth : kDefaultTlasMaxAreaGrowth;
    growth = float(s.tlasMotion.growth(s.tlasTransforms));
    if (!(growth <= maxGrowth) || s.tlasMotion.refitsSinceRebuild >= maxRefits) source = nullptr;
  }
  return source;
}

// The slot's TLAS object and storage, re-created when they are too small or were built without the update flag
// this build needs; its scratch, grown to the build's or refit's need.
Status ensureTlasObject(Impl& s, TlasSlot& slot, uint32_t slotIndex,
                        const VkAccelerationStructureBuildSizesInfoKHR& sizes, bool wantUpdate,
                        const TlasSlot*& source) {
  Context::Impl& c = s.c;
  bool flagsChanged = slot.allowsUpdate != wantUpdate;
  if (!slot.tlas || slot.storageCapacity < sizes.accelerationStructureSize || flagsChanged) {
    if (source == &slot) source = nullptr;  // rebuilding storage of the source itself
    if (slot.tlas) {
      VkAccelerationStructureKHR old = slot.tlas;
      c.retire([&c, old] { c.vk.vkDestroyAccelerationStructureKHR(c.desc.device, old, c.allocator()); });
      slot.tlas = VK_NULL_HANDLE;
      // Until this slot's new TLAS is built, nothing may refit from it (a failure below leaves it unbuilt).
      if (s.lastTlasSlot == slotIndex) s.lastTlasSlot = UINT32_MAX;
    }
    if (slot.storageCapacity < sizes.accelerationStructureSize) {
      retireBuffer(s.ctx, slot.storage);
      slot.storageCapacity = 0;  // a failure below leaves no storage: the next call creates it
      Status st = ensureBuffer(s.ctx, slot.storage, sizes.accelerationStructureSize,
                               VK_BUFFER_USAGE_ACCELERATION_STRUCTURE_STORAGE_BIT_KHR |
                                   VK_BUFFER_USAGE_SHADER_DEVICE_ADDRESS_BIT,
                               MemoryLocation::DeviceLocal, "TLAS storage");
      if (!st) return st;
      slot.storageCapacity = sizes.accelerationStructureSize;
    }
    Result<VkAccelerationStructureKHR> as = s.createAs(VK_ACCELERATION_STRUCTURE_TYPE_TOP_LEVEL_KHR,
                                                       slot.storage.buffer, 0, slot.storageCapacity);
    if (!as) return as.error();
    slot.tlas = as.value();
    slot.allowsUpdate = wantUpdate;
  }

  const VkDeviceSize align = s.scratchAlignment();
  VkDeviceSize scratchNeed = std::max(sizes.buildScratchSize, sizes.updateScratchSize) + align;
  return ensureBuffer(s.ctx, slot.scratch, scratchNeed,
                      VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | VK_BUFFER_USAGE_SHADER_DEVICE_ADDRESS_BIT,
                      MemoryLocation::DeviceLocal, "TLAS scratch");
}

// Copies the written instances (and shading records) into the slot's device-local buffers.
void recordInstanceCopies(const Context::Impl& c, VkCommandBuffer cmd, const TlasSlot& slot, uint32_t written,
                          bool records) {
  // The build and the shaders that read this slot's device copies before, and the copies that wrote them (a
  // service recorded twice into one command buffer across beginFrame()), are done before the copies overwrite
  // them (found by synchronization validation on the H200, where Auto copies).
  constexpr VkPipelineStageFlags readers = VK_PIPELINE_STAGE_ACCELERATION_STRUCTURE_BUILD_BIT_KHR |
                                           VK_PIPELINE_STAGE_RAY_TRACING_SHADER_BIT_KHR;
  recordMemoryBarrier(c.vk, cmd, readers | VK_PIPELINE_STAGE_TRANSFER_BIT,
                      VK_ACCESS_ACCELERATION_STRUCTURE_READ_BIT_KHR | VK_ACCESS_SHADER_READ_BIT |
                          VK_ACCESS_TRANSFER_WRITE_BIT,
                      VK_PIPELINE_STAGE_TRANSFER_BIT, VK_ACCESS_TRANSFER_WRITE_BIT);
  const VkBufferCopy instanceRegion{0, 0, VkDeviceSize(written) * sizeof(VkAccelerationStructureInstanceKHR)};
  c.vk.vkCmdCopyBuffer(cmd, slot.instances.buffer, slot.deviceInstances.buffer, 1, &instanceRegion);
  if (records) {
    const VkBufferCopy recordRegion{0, 0, VkDeviceSize(written) * sizeof(ShadingRecord)};
    c.vk.vkCmdCopyBuffer(cmd, slot.shading.buffer, slot.deviceShading.buffer, 1, &recordRegion);
  }
  recordMemoryBarrier(c.vk, cmd, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_ACCESS_TRANSFER_WRITE_BIT, readers,
                      VK_ACCESS_ACCELERATION_STRUCTURE_READ_BIT_KHR | VK_ACCESS_SHADER_READ_BIT);
}

// The counters, the Adaptive measure's chain and the slot's record of what it was built from.
uint32_t commitTlasBuild(Impl& s, TlasSlot& slot, uint32_t slotIndex, const TlasBuildOptions& options,
                         VkBuildAccelerationStructureFlagsKHR flags, const WrittenInstances& w, bool refit,
                         uint64_t serial, float& growth) {
  if (refit) {
    ++s.counters.tlasRefits;
  } else {
    ++s.counters.tlasBuilds;
  }
  uint32_t refitsSinceRebuild = 0;
  if (options.mode == TlasBuildMode::Adaptive) {
    if (refit) {
      refitsSinceRebuild = ++s.tlasMotion.refitsSinceRebuild;
    } else {
      s.tlasMotion.reset(s.tlasTransforms);
      growth = 1.0f;
    }
    s.tlasMotionSerial = serial;
  }
  slot.builtFlags = flags;
  slot.builtInstanceCount = w.written;
  slot.blasSignature = w.signature;
  s.lastTlasSlot = slotIndex;
  s.counters.lastTlasInstances = w.written;
  s.counters.staleBlas = w.stale;
  return refitsSinceRebuild;
}

}  // namespace

Result<TlasInfo> AccelerationStructureService::recordTlasBuild(VkCommandBuffer cmd, std::span<const Instance> instances,
                                                               const TlasBuildOptions& options) {
  Impl& s = *impl_;
  Context::Impl& c = s.c;
  std::lock_guard<std::mutex> lock(s.mutex);
  s.handOnDeferredRetires();
  if (!cmd) return Error{ErrorCode::InvalidArgument, VK_SUCCESS, "recordTlasBuild: cmd is VK_NULL_HANDLE"};
  if (Status st = validateTlasOptions(c, instances.size(), options); !st) return st.error();
  const uint32_t slotIndex = static_cast<uint32_t>(c.frame % c.desc.framesInFlight);
  TlasSlot& slot = s.tlasSlots[slotIndex];
  if (slot.writtenFrame == c.frame) {
    // The slot's instance buffer is read when the command buffer executes: a second list would overwrite
    // the first before the GPU reads it.
    return Error{ErrorCode::InvalidArgument, VK_SUCCESS,
                 "recordTlasBuild: already called in frame " + std::to_string(c.frame) +
                     "; call Context::beginFrame() between frames, or use a second AccelerationStructureService "
                     "for a second TLAS in one frame"};
  }
  const uint32_t count = static_cast<uint32_t>(instances.size());
  const bool copyInstances = options.instanceUpload == TlasInstanceUpload::CopyToDevice ||
                             (options.instanceUpload == TlasInstanceUpload::Auto && !hostMemoryIsDeviceLocal(c));
  if (Status st = prepareInstanceBuffers(s, slot, count, options, copyInstances); !st) return st.error();
  if (Status st = validateInstances(s, instances); !st) return st.error();

  slot.writtenFrame = c.frame;
  const uint64_t serial = s.tlasSerial + 1;
  const WrittenInstances w = writeInstances(s, slot, instances, options, serial);
  s.tlasSerial = serial;
  retireFrameMarker(s);

  VkAccelerationStructureGeometryKHR geometry{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_KHR};
  geometry.geometryType = VK_GEOMETRY_TYPE_INSTANCES_KHR;
  geometry.geometry.instances.sType = VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_INSTANCES_DATA_KHR;
  geometry.geometry.instances.arrayOfPointers = VK_FALSE;
  geometry.geometry.instances.data.deviceAddress = copyInstances ? slot.deviceInstances.address
                                                                 : slot.instances.address;

  // Both refitting modes build with ALLOW_UPDATE, so one can follow the other without a rebuild.
  const bool wantUpdate = options.mode != TlasBuildMode::Rebuild;
  VkAccelerationStructureBuildGeometryInfoKHR info{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_BUILD_GEOMETRY_INFO_KHR};
  info.type = VK_ACCELERATION_STRUCTURE_TYPE_TOP_LEVEL_KHR;
  info.flags = (options.preference == TlasBuildPreference::FastBuild
                    ? VK_BUILD_ACCELERATION_STRUCTURE_PREFER_FAST_BUILD_BIT_KHR
                    : VK_BUILD_ACCELERATION_STRUCTURE_PREFER_FAST_TRACE_BIT_KHR) |
               (wantUpdate ? VK_BUILD_ACCELERATION_STRUCTURE_ALLOW_UPDATE_BIT_KHR : 0);
  float growth = 0.0f;
  const TlasSlot* source = chooseRefitSource(s, options, info.flags, w, serial, growth);
  info.geometryCount = 1;
  info.pGeometries = &geometry;
  // Sized for the buffer's capacity so small fluctuations in the instance count reuse the same storage.
  uint32_t sizeFor = std::max(slot.instanceCapacity, 1u);
  VkAccelerationStructureBuildSizesInfoKHR sizes{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_BUILD_SIZES_INFO_KHR};
  c.vk.vkGetAccelerationStructureBuildSizesKHR(c.desc.device, VK_ACCELERATION_STRUCTURE_BUILD_TYPE_DEVICE_KHR, &info,
                                               &sizeFor, &sizes);
  if (Status st = ensureTlasObject(s, slot, slotIndex, sizes, wantUpdate, source); !st) return st.error();

  info.mode = source ? VK_BUILD_ACCELERATION_STRUCTURE_MODE_UPDATE_KHR : VK_BUILD_ACCELERATION_STRUCTURE_MODE_BUILD_KHR;
  info.srcAccelerationStructure = source ? source->tlas : VK_NULL_HANDLE;
  info.dstAccelerationStructure = slot.tlas;
  info.scratchData.deviceAddress = alignUp(slot.scratch.address, s.scratchAlignment());
  VkAccelerationStructureBuildRangeInfoKHR range{};
  range.primitiveCount = w.written;
  const VkAccelerationStructureBuildRangeInfoKHR* rangePtr = &range;

  if (copyInstances && w.written) recordInstanceCopies(c, cmd, slot, w.written, options.writeShadingRecords);
  // Earlier BLAS builds and this slot's previous use of its scratch must be complete.
  recordAsBarrier(c.vk, cmd, VK_PIPELINE_STAGE_ACCELERATION_STRUCTURE_BUILD_BIT_KHR);
  c.vk.vkCmdBuildAccelerationStructuresKHR(cmd, 1, &info, &rangePtr);
  recordAsBarrier(
      c.vk, cmd, VK_PIPELINE_STAGE_RAY_TRACING_SHADER_BIT_KHR | VK_PIPELINE_STAGE_ACCELERATION_STRUCTURE_BUILD_BIT_KHR);
  const uint32_t refitsSinceRebuild = commitTlasBuild(s, slot, slotIndex, options, info.flags, w, source != nullptr,
                                                      serial, growth);

  TlasInfo result;
  result.tlas = slot.tlas;
  VkAccelerationStructureDeviceAddressInfoKHR ai{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_DEVICE_ADDRESS_INFO_KHR};
  ai.accelerationStructure = slot.tlas;
  result.address = c.vk.vkGetAccelerationStructureDeviceAddressKHR(c.desc.device, &ai);
  result.instanceCount = w.written;
  result.skippedInstances = w.skipped;
  result.failedInstances = w.failed;
  result.nonOpaqueInstances = w.nonOpaque;
  result.updated = source != nullptr;
  result.areaGrowth = growth;
  result.refitsSinceRebuild = refitsSinceRebuild;
  for (int i = 0; i < 3; ++i) result.originOffset[i] = options.originOffset[i];
  if (options.writeShadingRecords) {
    result.shadingRecords = copyInstances ? slot.deviceShading.buffer : slot.shading.buffer;
    result.shadingRecordsBytes = VkDeviceSize(std::max(w.written, 1u)) * sizeof(ShadingRecord);
  }
  return result;
}

}  // namespace rb
