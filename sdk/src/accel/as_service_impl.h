// Internal state of the acceleration-structure service, shared by its parts: the BLAS side (as_service.cpp,
// as_registration.cpp, as_builds.cpp, as_compaction.cpp, as_mesh_state.cpp, as_stats.cpp, dynamic_*.cpp) and the
// TLAS side (tlas_builder.cpp).
#pragma once

#include <raybridge/acceleration_structures.h>

#include <atomic>
#include <deque>
#include <functional>
#include <memory>
#include <mutex>
#include <string>
#include <unordered_map>
#include <vector>

#include "as_storage_allocator.h"
#include "async_submitter.h"
#include "cluster_bounds.h"
#include "context_impl.h"
#include "gpu_memory.h"
#include "mesh_validation.h"
#include "tlas_motion.h"

namespace rb {

constexpr size_t kMaxBatchTimings = 64;  // AsStats::batches keeps the most recent ones

enum class BlasState : uint8_t {
  Free,     // slot unused (its generation is bumped on reuse)
  Queued,   // registered, build not yet recorded
  Built,    // build recorded; usable by TLAS builds recorded after it
  Failed,   // static only: its latest build attempt failed (BlasEntry::failure); in failedBuilds or the queue
  Evicted,  // static only: evictMesh freed its BLAS; registrations keep it, it holds no storage nor budget
};

// One copy of a dynamic BLAS; the copies of a mesh form a ring (see DynamicBuildMode).
struct BlasCopy {
  VkAccelerationStructureKHR as = VK_NULL_HANDLE;
  StorageAllocation storage;
  VkDeviceAddress address = 0;
  bool written = false;
  uint64_t writeSerial = 0;    // order of the writes over the mesh's copies (the newest has the largest)
  uint64_t writtenFrame = 0;   // Context frame of the work that wrote it last
  uint64_t pose = 0;           // DynamicBlas::pose it was built or refit from
  uint64_t signalValue = 0;    // async timeline value of that work; 0 = recorded on the main queue
  bool used = false;           // referenced by a TLAS since it was created
  uint64_t lastUsedFrame = 0;  // frame of the last TLAS that referenced it
};

// Refit/rebuild state of a dynamic BLAS.
struct DynamicBlas {
  std::vector<BlasCopy> copies;  // empty until the first build is planned
  uint32_t newest = 0;           // copy written last
  uint64_t writes = 0;           // writes so far (BlasCopy::writeSerial)
  bool updatePending = false;    // updateMesh since the last refit or build
  bool forceRebuild = false;
  bool resize = false;  // forceRebuild with new counts: the copies are re-created at the rebuild
  uint64_t pose = 0;    // updateMesh calls so far: the pose the engine's buffers hold
  uint32_t refitsSinceBuild = 0;
  uint32_t buildGeneration = 0;  // full builds so far; measure samples carry it, so late ones are ignored
  double baselineArea = 0.0;     // refit-quality measure at the last full build (0 = not read back yet)
  double ratio = 0.0;            // latest measure / baseline
  bool overThreshold = false;    // ratio > RefitPolicy::maxAreaGrowth
  uint64_t waitingSince = 0;     // frame since which it waits for a rebuild (staggering order)
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
  VkDeviceSize builtSize = 0;      // size of the original build (of one copy, for a dynamic BLAS)
  VkDeviceSize currentSize = 0;    // size now (smaller once compacted)
  VkDeviceSize reserved = 0;       // storage it holds against the budget (aligned, all copies)
  DynamicBlas dyn;                 // MeshRole::Dynamic only; `as` and `address` then mirror the newest copy
  bool compactionPending = false;  // waiting for its compacted-size query
  VkDeviceSize compactedSize = 0;  // known and worth a copy: copy queued
  bool compacted = false;
  uint64_t lastUsedFrame = 0;   // frame of the last TLAS that referenced it
  uint64_t lastTlasSerial = 0;  // serial of the last TLAS that referenced it
  uint64_t releasedOrder = 0;   // LRU order among released entries
  Error failure;                // BlasState::Failed: why (MeshStatus::error)
};

// One registerMesh call: what a MeshHandle names. Registrations of equal geometry share one BlasEntry but
// keep their own buffers and attributes (read by shading records) and their own lifetime.
struct Registration {
  uint32_t generation = 0;
  bool live = false;
  uint32_t blas = 0;  // BlasEntry index
  ValidatedMesh mesh;
  MeshBounds poseBounds;  // the latest MeshUpdate::bounds; not given() = mesh.desc.bounds
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

// A measure read back for one dynamic BLAS: the cluster areas at [firstCluster, firstCluster + clusterCount).
struct ClusterSample {
  uint32_t entry = 0;
  uint32_t entryGeneration = 0;
  uint32_t buildGeneration = 0;  // DynamicBlas::buildGeneration after this work
  bool build = false;            // measured for a full build: the new baseline
  uint32_t firstCluster = 0;
  uint32_t clusterCount = 0;
};

// One frame's dynamic work, waiting for its GPU results (measures, async timings).
struct DynamicSubmission {
  uint64_t frame = 0;
  uint64_t timelineValue = 0;  // async: the value it signals; 0 = recorded on the main queue (frameDone)
  GpuBuffer readback;          // host-visible cluster areas; invalid when nothing was measured
  std::vector<ClusterSample> samples;
  VkQueryPool timestamps = VK_NULL_HANDLE;  // async submissions (main-queue work is a BuildBatch)
  uint32_t builds = 0;
  uint64_t triangles = 0;
};

// What a frame's dynamic work does to one BLAS.
struct DynamicOp {
  enum Kind : uint8_t { FirstBuild, Refit, Rebuild } kind = Refit;
  uint32_t entry = 0;
  uint32_t src = 0;  // copy read (refit)
  uint32_t dst = 0;  // copy written
  bool measure = false;
  std::vector<BlasCopy> replacement;  // resize: the new copies (dst indexes them)
};

struct TlasSlot {
  VkAccelerationStructureKHR tlas = VK_NULL_HANDLE;
  GpuBuffer storage;
  GpuBuffer scratch;
  GpuBuffer instances;  // host-visible VkAccelerationStructureInstanceKHR array
  // Device-local copy of `instances` the build reads (TlasInstanceUpload::CopyToDevice); grown with it.
  GpuBuffer deviceInstances;
  GpuBuffer shading;        // host-visible ShadingRecord array (only with writeShadingRecords)
  GpuBuffer deviceShading;  // its device-local copy the shaders read, like deviceInstances
  uint32_t instanceCapacity = 0;
  VkDeviceSize storageCapacity = 0;
  bool allowsUpdate = false;
  VkBuildAccelerationStructureFlagsKHR builtFlags = 0;  // of the last build: a refit must repeat them
  uint32_t builtInstanceCount = 0;
  uint64_t blasSignature = 0;          // hash of the BLAS addresses in order, to decide if a refit is valid
  uint64_t writtenFrame = UINT64_MAX;  // frame whose instances the buffer holds
};

struct AccelerationStructureService::Impl {
  Context& ctx;
  Context::Impl& c;
  AsServiceDesc desc;

  // Thread safety (see the public header): every public call holds `mutex` while it touches the members
  // below, so registerMesh/releaseMesh (a streaming thread) and the recording calls exclude each other.
  // The Context's deferred-release queue and frame counter are not guarded by it (beginFrame runs on the
  // recording thread without it), so registerMesh/releaseMesh never call Context::Impl::retire nor read
  // Context::Impl::frame: their retires wait in `deferredRetires` until the next recording call hands them
  // on (later than asked, which is only safer), and eviction learns which frames are done from
  // `framesDoneBelow`.
  std::mutex mutex;
  bool deferRetires = false;  // set while registerMesh/releaseMesh run
  std::vector<std::function<void()>> deferredRetires;
  // Every frame below it is known to be done on the GPU: each recordTlasBuild retires a marker that raises it
  // past that frame, so it advances exactly when Context::frameDone() would say so (beginFrame,
  // releaseAfterIdle). Written when the Context releases a marker (beginFrame, without `mutex`), read by
  // eviction; the markers share it, so they never depend on the service's lifetime.
  std::shared_ptr<std::atomic<uint64_t>> framesDoneBelow = std::make_shared<std::atomic<uint64_t>>(0);
  bool frameKnownDone(uint64_t frame) const { return frame < framesDoneBelow->load(); }
  // The Context's retire(), or deferredRetires while a registration call runs.
  void retire(std::function<void()> release);
  // Called under `mutex` by every call other than registerMesh/releaseMesh, on the recording thread.
  void handOnDeferredRetires();
  AsStorageAllocator storage;
  std::vector<BlasEntry> entries;
  std::vector<uint32_t> freeSlots;
  std::vector<Registration> registrations;  // index 0 unused: a zero handle is the null handle
  std::vector<uint32_t> freeRegistrations;
  std::unordered_map<uint64_t, uint32_t> byKey;
  std::deque<uint32_t> queue;  // entry indices waiting for a build, in registration order
  // Failed entries waiting for their retry: the next recordPendingWork moves them to the back of `queue`.
  std::vector<uint32_t> failedBuilds;
  // Build scratch of the main queue, grown to what the builds need (up to scratchBudgetBytes) and released when the
  // builds stop needing most of it (sharedScratch, trimSharedScratch).
  GpuBuffer scratch;
  VkDeviceSize scratchNeedInWindow = 0;  // the most scratch one recording call needed in the current window
  uint32_t scratchWindowCalls = 0;       // recording calls in the current window
  std::vector<BuildBatch> inFlightBatches;
  std::vector<VkQueryPool> freeTimestampPools;
  std::vector<BuildBatchTiming> timings;
  Status queryError;  // see resolveBatches()
  std::vector<TlasSlot> tlasSlots;
  uint64_t tlasSerial = 0;
  uint32_t lastTlasSlot = UINT32_MAX;  // slot of the TLAS recorded last
  TlasMotionMeasure tlasMotion;        // TlasBuildMode::Adaptive's refit-quality measure
  std::vector<float> tlasTransforms;   // scratch: the written instances' transforms, 12 floats each (Adaptive)
  uint64_t tlasMotionSerial = 0;       // the TLAS (tlasSerial) whose build last updated tlasMotion
  uint64_t releaseCounter = 0;
  VkDeviceSize reservedBytes = 0;     // storage of all live BLASes (aligned), for the budget
  VkDeviceSize releasedCacheCap = 0;  // AsServiceDesc::releasedCacheBytes resolved (0 with disableReleasedCache)
  AsStats counters;                   // the cumulative counters (registrations, dedupHits, evictions, ...)

  // Dynamic meshes (dynamic_blas.cpp).
  RefitPolicy policy;          // defaults resolved
  uint32_t dynamicCopies = 1;  // copies per dynamic BLAS
  bool async = false;          // dynamic work on the async queue
  AsyncSubmitter submitter;
  std::unique_ptr<AsStorageAllocator> dynamicStorage;  // async: concurrent over both families
  ClusterBoundsPass clusterBounds;
  bool clusterBoundsCreated = false;
  GpuBuffer asyncScratch;
  uint64_t asyncTimestampMask = 0;                    // 0 = no timestamps on the async queue
  std::vector<DynamicSubmission> dynamicSubmissions;  // in order
  std::vector<GpuBuffer> freeReadbacks;
  std::vector<VkQueryPool> freeAsyncTimestampPools;
  struct AsyncRelease {
    uint64_t value;  // the async timeline reaches it once the GPU no longer uses the object
    std::function<void()> release;
  };
  std::vector<AsyncRelease> asyncReleases;
  uint64_t lastDynamicWriteFrame = UINT64_MAX;  // frame whose dynamic work wrote copies
  uint64_t lastVertexReadValue = 0;             // async value of the latest submission that read vertex buffers

  Impl(Context& context, const AsServiceDesc& d);
  ~Impl();

  // The live registration a handle names (errors name the call, `what`).
  Result<Registration*> lookup(MeshHandle h, const char* what);
  uint32_t liveRegistrations() const;
  void destroyEntry(uint32_t index);  // retires its AS and storage; frees the slot
  Status makeRoom(VkDeviceSize bytes, const std::string& forWhat);
  // The least recently released cached BLAS (no registration left) that no TLAS in flight references; 0 = none.
  uint32_t cachedVictim() const;
  // Frees cached BLASes, least recently released first, while they hold more than releasedCacheCap (those in
  // flight wait for a later call: releaseMesh and every recordPendingWork call it).
  void trimReleasedCache();
  // Mesh states (as_mesh_state.cpp).
  std::string meshName(const BlasEntry& e) const;  // "mesh 'name'", or the handle of its source registration
  // Failed with `error` (the message as given), waiting in failedBuilds for the next recordPendingWork.
  void markBuildFailed(uint32_t index, Error error);
  // Frees the entry's BLAS (retired: frames in flight keep it) and its budget: BlasState::Evicted.
  void evictEntry(uint32_t index);
  // Evicted -> Queued, reserving its storage against the budget (makeRoom's error when it cannot).
  Status requeueEvicted(uint32_t index, const std::string& forWhat);
  // Moves the failed builds to the back of the queue (those failed for the budget reserve again first, or stay
  // Failed with the new error, kept in `failure` when it is the first of the call).
  void retryFailedBuilds(Status& failure);
  // Reads the queries of the batches whose frames are done, and releases them. A failed read (a lost device) is
  // kept in queryError, which the next recordPendingWork() returns.
  void resolveBatches();
  void addTiming(const BuildBatchTiming& timing);
  Status recordCompactions(VkCommandBuffer cmd, bool& recordedAny);
  // Records one batch of builds. A mesh whose BLAS cannot be created is marked Failed and left out (the first
  // such error goes to `meshFailure`); any other failure puts the batch back at the front of the queue and is
  // returned.
  Status recordBuildBatch(VkCommandBuffer cmd, std::vector<uint32_t>& batch, VkDeviceSize scratchBytes,
                          bool& recordedAny, Status& meshFailure);
  Result<VkAccelerationStructureKHR> createAs(VkAccelerationStructureTypeKHR type, VkBuffer buffer, VkDeviceSize offset,
                                              VkDeviceSize size);
  void buildGeometry(const BlasEntry& e, VkAccelerationStructureGeometryKHR& geometry,
                     VkAccelerationStructureBuildRangeInfoKHR& range) const;
  VkBuildAccelerationStructureFlagsKHR blasFlags(const BlasEntry& e) const;
  // Fills e.sizes from the driver for e.mesh built with blasFlags(e) (thread-safe: no service state).
  void queryBuildSizes(BlasEntry& e) const;
  // Takes a 2-query timestamp pool from `pools`, creating one when it is empty.
  Result<VkQueryPool> takeTimestampPool(std::vector<VkQueryPool>& pools, const char* what);
  VkDeviceSize scratchAlignment() const;
  // `buffer` (scratch, or the async queue's) holding at least `need` bytes, grown when it is smaller: to twice its
  // size or `need`, whichever is more, at most `cap` (a larger need gets it exactly). Returns its aligned address.
  Result<VkDeviceAddress> growScratch(GpuBuffer& buffer, VkDeviceSize need, VkDeviceSize cap, const char* what);
  // The main queue's scratch for `need` bytes (growScratch up to the budget), counted in the shrink window.
  Result<VkDeviceAddress> sharedScratch(VkDeviceSize need);
  // Ends one recording call for the shrink window: every kScratchWindowCalls calls, the scratch is released
  // when the window's largest need was at most a quarter of it (the next need creates it again at its size).
  void trimSharedScratch();
  VkDeviceSize storageNeed(const BlasEntry& e) const;  // aligned storage of all its copies

  // Dynamic meshes (dynamic_blas.cpp).
  Status initDynamic(const AsServiceDesc& d);
  void destroyDynamic();
  bool lateMode() const { return desc.dynamicMode == DynamicBuildMode::AsyncOneFrameLate; }
  AsStorageAllocator& copyStorage() { return dynamicStorage ? *dynamicStorage : storage; }
  // The copy this frame's TLAS references (-1: none written yet).
  int32_t tlasCopy(const BlasEntry& e) const;
  Result<std::vector<BlasCopy>> createCopies(const BlasEntry& e);
  void retireCopies(std::vector<BlasCopy>& copies);
  // Retires through the Context once the async timeline shows the GPU past every submission so far.
  void retireAfterAsync(std::function<void()> release);
  // Hands `buffer` to retireAfterAsync (destroyed once nothing in flight can use it) and leaves it empty.
  void retireBufferAfterAsync(GpuBuffer& buffer);
  void releaseAsyncRetired();
  void resolveDynamicSubmissions();
  // Plans, records and commits one frame's dynamic work into `cmd` (the engine's command buffer in the
  // in-frame modes); `trianglesUsed` counts first builds against maxBuildTrianglesPerCall.
  Status recordDynamicWork(VkCommandBuffer cmd, uint64_t& trianglesUsed, bool& recordedAny);
  Result<std::vector<DynamicOp>> planDynamicWork(uint64_t& trianglesUsed);
  Status recordDynamicOps(VkCommandBuffer cmd, std::vector<DynamicOp>& ops, bool onAsyncQueue, DynamicSubmission& sub,
                          std::vector<GpuBuffer>& transientScratch);
  void commitDynamicOps(std::vector<DynamicOp>& ops, uint64_t signalValue);
};

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
