// Internal state of the acceleration-structure service, shared by the BLAS side (as_service.cpp) and the
// TLAS side (tlas_builder.cpp).
#pragma once

#include <raybridge/acceleration_structures.h>

#include <deque>
#include <unordered_map>
#include <vector>

#include "as_storage_allocator.h"
#include "context_impl.h"
#include "gpu_memory.h"
#include "mesh_validation.h"

namespace rb {

enum class BlasState : uint8_t {
  Free,     // slot unused (its generation is bumped on reuse)
  Queued,   // registered, build not yet recorded
  Built,    // build recorded; usable by TLAS builds recorded after it
};

struct BlasEntry {
  uint32_t generation = 0;
  BlasState state = BlasState::Free;
  uint32_t refCount = 0;  // live registrations sharing this BLAS
  uint64_t key = 0;
  // The buffers builds and refits read: those of `sourceRegistration`, a live registration, switched to
  // another one when it is released, so a BLAS never reads buffers their owner may have freed.
  ValidatedMesh mesh;
  uint32_t sourceRegistration = 0;
  VkAccelerationStructureBuildSizesInfoKHR sizes{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_BUILD_SIZES_INFO_KHR};
  VkAccelerationStructureKHR as = VK_NULL_HANDLE;
  StorageAllocation storage;
  VkDeviceAddress address = 0;
  VkDeviceSize builtSize = 0;    // size of the original build
  VkDeviceSize currentSize = 0;  // size now (smaller once compacted)
  bool needsRefit = false;
  bool compactionPending = false;       // waiting for its compacted-size query
  VkDeviceSize compactedSize = 0;       // known and worth a copy: copy queued
  bool compacted = false;
  uint64_t lastUsedFrame = 0;   // frame of the last TLAS that referenced it
  uint64_t lastTlasSerial = 0;  // serial of the last TLAS that referenced it
  uint64_t releasedOrder = 0;   // LRU order among released entries
};

// One registerMesh call: what a MeshHandle names. Registrations of equal geometry share one BlasEntry but
// keep their own buffers and attributes (read by shading records) and their own lifetime.
struct Registration {
  uint32_t generation = 0;
  bool live = false;
  uint32_t blas = 0;  // BlasEntry index
  ValidatedMesh mesh;
};

// One recorded build batch whose queries resolve once its frame is done.
struct BuildBatch {
  uint64_t frame = 0;
  VkQueryPool timestamps = VK_NULL_HANDLE;  // 2 queries; VK_NULL_HANDLE when timing is off
  VkQueryPool compactedSizes = VK_NULL_HANDLE;
  std::vector<uint32_t> compactEntries;  // entry index per compacted-size query
  std::vector<uint32_t> compactGenerations;
  uint32_t builds = 0;
  uint64_t triangles = 0;
};

struct TlasSlot {
  VkAccelerationStructureKHR tlas = VK_NULL_HANDLE;
  GpuBuffer storage;
  GpuBuffer scratch;
  GpuBuffer instances;  // host-visible VkAccelerationStructureInstanceKHR array
  GpuBuffer shading;    // host-visible ShadingRecord array (only with writeShadingRecords)
  uint32_t instanceCapacity = 0;
  VkDeviceSize storageCapacity = 0;
  bool allowsUpdate = false;
  uint32_t builtInstanceCount = 0;
  uint64_t blasSignature = 0;  // hash of the BLAS addresses in order, to decide if a refit is valid
  uint64_t writtenFrame = UINT64_MAX;  // frame whose instances the buffer holds
};

struct AccelerationStructureService::Impl {
  Context& ctx;
  Context::Impl& c;
  AsServiceDesc desc;
  AsStorageAllocator storage;
  std::vector<BlasEntry> entries;
  std::vector<uint32_t> freeSlots;
  std::vector<Registration> registrations;  // index 0 unused: a zero handle is the null handle
  std::vector<uint32_t> freeRegistrations;
  std::unordered_map<uint64_t, uint32_t> byKey;
  std::deque<uint32_t> queue;  // entry indices waiting for a build, in registration order
  GpuBuffer scratch;           // persistent build scratch (scratchBudgetBytes)
  std::vector<BuildBatch> inFlightBatches;
  std::vector<VkQueryPool> freeTimestampPools;
  std::vector<BuildBatchTiming> timings;
  std::vector<TlasSlot> tlasSlots;
  uint64_t tlasSerial = 0;
  uint32_t lastTlasSlot = UINT32_MAX;  // slot of the TLAS recorded last
  uint64_t releaseCounter = 0;
  VkDeviceSize reservedBytes = 0;  // storage of all live BLASes (aligned), for the budget
  AsStats counters;                // the cumulative counters (registrations, dedupHits, evictions, ...)

  Impl(Context& context, const AsServiceDesc& d);
  ~Impl();

  // The live registration a handle names (errors name the call, `what`).
  Result<Registration*> lookup(MeshHandle h, const char* what);
  uint32_t liveRegistrations() const;
  void destroyEntry(uint32_t index);  // retires its AS and storage; frees the slot
  Status makeRoom(VkDeviceSize bytes, const std::string& forWhat);
  void resolveBatches();
  Status recordCompactions(VkCommandBuffer cmd, bool& recordedAny);
  Status recordBuildBatch(VkCommandBuffer cmd, std::vector<uint32_t>& batch, bool refit, VkDeviceSize scratchBytes,
                          bool& recordedAny);
  Result<VkAccelerationStructureKHR> createAs(VkAccelerationStructureTypeKHR type, VkBuffer buffer,
                                              VkDeviceSize offset, VkDeviceSize size);
  void buildGeometry(const BlasEntry& e, VkAccelerationStructureGeometryKHR& geometry,
                     VkAccelerationStructureBuildRangeInfoKHR& range) const;
  VkBuildAccelerationStructureFlagsKHR blasFlags(const BlasEntry& e) const;
  VkDeviceSize scratchAlignment() const;
};

// Where a TLAS instance's surface data is, for hit shading (mirrors ShadingRecord in
// shaders/raybridge_shading_records.glsl).
struct ShadingRecord {
  uint64_t positions, indices, normals, texcoords;
  uint32_t positionStride, normalStride, texcoordStride, indexType;  // indexType: 0 u32, 1 u16, 2 none
  uint32_t material, positionFormat, pad0, pad1;
};
static_assert(sizeof(ShadingRecord) == 64, "must match shaders/raybridge_shading_records.glsl");

void recordAsBarrier(const DeviceFunctions& vk, VkCommandBuffer cmd, VkPipelineStageFlags dstStages);

}  // namespace rb
