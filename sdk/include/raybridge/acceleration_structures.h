// Acceleration structures as a service: one BLAS per distinct mesh (content-hash dedup), batched builds
// under a scratch budget, compaction, suballocated storage, a TLAS per frame, LRU eviction under a memory
// budget, statistics.
//
// Frame flow, all recorded into the engine's command buffers:
//   ctx.beginFrame();                       // after waiting for the frame slot's fence
//   service.registerMesh(...)               // any time; returns at once, the build is only queued
//   service.recordPendingWork(cmd);         // compaction copies, queued builds and refits, within budgets
//   service.recordTlasBuild(cmd, instances) // TLAS over the meshes built so far; ready for ray tracing
//
// Engine buffers are read in place, never copied. Vertex and index buffers must be created with
//   VK_BUFFER_USAGE_SHADER_DEVICE_ADDRESS_BIT | VK_BUFFER_USAGE_ACCELERATION_STRUCTURE_BUILD_INPUT_READ_ONLY_BIT_KHR
// (and memory allocated with VK_MEMORY_ALLOCATE_DEVICE_ADDRESS_BIT). They must stay alive and unchanged
// while their mesh is registered (a dynamic mesh may change between updateMesh() calls).
//
// Thread safety: externally synchronised, like the Context it was created from.
#pragma once

#include <raybridge/context.h>

#include <cstdint>
#include <memory>
#include <span>
#include <vector>

namespace rb {

// A registered mesh. The generation detects stale handles: a handle whose mesh was evicted or destroyed is
// rejected with ErrorCode::StaleHandle instead of reaching the GPU. A zero handle is the null handle.
struct MeshHandle {
  uint32_t index = 0;
  uint32_t generation = 0;  // 0 = null handle
  bool isNull() const { return generation == 0; }
  friend bool operator==(MeshHandle, MeshHandle) = default;
};

enum class IndexType : uint8_t {
  Uint32 = 0,  // default
  Uint16,
  None,  // non-indexed: every three consecutive vertices form a triangle
};

// The role picks the build flags.
enum class MeshRole : uint8_t {
  Static = 0,  // default: PREFER_FAST_TRACE + ALLOW_COMPACTION, compacted after its build
  Dynamic,     // deforming: PREFER_FAST_BUILD + ALLOW_UPDATE, refit by updateMesh(); never compacted
};

// Describes one mesh from the engine's own buffers.
struct MeshDesc {
  VkDeviceAddress vertexAddress = 0;   // required: device address of the first vertex position
  VkDeviceSize vertexBufferBytes = 0;  // required: bytes readable from vertexAddress (bounds-checks the counts)
  uint32_t vertexCount = 0;            // required: vertices addressed by this mesh
  VkFormat vertexFormat = VK_FORMAT_UNDEFINED;  // UNDEFINED = VK_FORMAT_R32G32B32_SFLOAT
  uint32_t vertexStride = 0;                    // 0 = the size of vertexFormat (tightly packed positions)
  IndexType indexType = IndexType::Uint32;      // default Uint32
  VkDeviceAddress indexAddress = 0;   // required unless indexType is None
  VkDeviceSize indexBufferBytes = 0;  // required unless indexType is None: bytes readable from indexAddress
  uint32_t triangleCount = 0;         // required, > 0: triangles read (indexCount / 3, or vertexCount / 3)
  MeshRole role = MeshRole::Static;   // default Static
  bool nonOpaque = false;             // false = opaque: any-hit shaders are skipped for this geometry
  // Dedup: meshes with equal keys share one BLAS. Dynamic meshes deform independently, so they are deduplicated
  // only by an explicit contentKey. 0 = derive the key: a 64-bit hash of hostVertices and
  // hostIndices when both are given (or hostVertices for non-indexed meshes), else the buffer identity
  // (addresses, counts, format, stride), which shares a BLAS only between registrations of the same range.
  uint64_t contentKey = 0;
  const void* hostVertices = nullptr;  // optional CPU copy, laid out like the GPU buffer (vertexCount*stride)
  const void* hostIndices = nullptr;   // optional CPU copy of the indices (triangleCount*3 indices)
  const char* debugName = nullptr;     // optional; appears in error messages

  // Optional vertex attributes, read (by device address, in place) where reflection rays hit the mesh. The
  // same vertex indexing as the positions. 0 = absent: hits use the triangle's geometric normal and
  // texture coordinate (0, 0). The buffers need VK_BUFFER_USAGE_SHADER_DEVICE_ADDRESS_BIT.
  VkDeviceAddress normalAddress = 0;    // R32G32B32_SFLOAT object-space normals
  uint32_t normalStride = 0;            // 0 = 12
  VkDeviceAddress texcoordAddress = 0;  // R32G32_SFLOAT texture coordinates (glTF convention, v down)
  uint32_t texcoordStride = 0;          // 0 = 8
};

// One TLAS instance. Instance{} is the identity transform, visible to every ray mask.
struct Instance {
  MeshHandle mesh;  // required
  // Row-major 3x4 object-to-world matrix (the layout of VkTransformMatrixKHR). Default identity.
  float transform[12] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0};
  uint32_t customIndex = 0;  // 24 bits; gl_InstanceCustomIndexEXT
  uint8_t mask = 0xFF;       // default: visible to all rays
  uint32_t sbtRecordOffset = 0;
  VkGeometryInstanceFlagsKHR flags = 0;
  uint32_t material = 0;  // index into ReflectionPass::setMaterials(); read only by passes that shade hits
};

enum class TlasBuildMode : uint8_t {
  Rebuild = 0,       // default: a full build every frame (best trace speed after large motion)
  UpdateIfPossible,  // refit the previous frame's TLAS when the instance list has the same meshes and count
};

struct TlasBuildOptions {
  TlasBuildMode mode = TlasBuildMode::Rebuild;
  // Subtracted (in double precision) from every instance's translation, so a camera-relative TLAS keeps full
  // float precision far from the world origin. Default 0: world space.
  double originOffset[3] = {0.0, 0.0, 0.0};
  // Also write, per TLAS instance, where its vertex data and material are (TlasInfo::shadingRecords), for
  // passes that shade the surfaces rays hit (reflections). false = no such buffer is allocated.
  bool writeShadingRecords = false;
};

struct TlasInfo {
  VkAccelerationStructureKHR tlas = VK_NULL_HANDLE;
  VkDeviceAddress address = 0;
  uint32_t instanceCount = 0;    // instances written into the TLAS
  uint32_t skippedInstances = 0; // instances whose mesh has no built BLAS yet (queued beyond the budget)
  bool updated = false;          // true if refit rather than rebuilt
  double originOffset[3] = {0.0, 0.0, 0.0};  // TlasBuildOptions::originOffset it was built with
  // With TlasBuildOptions::writeShadingRecords: a storage buffer of one record per TLAS instance (indexed by
  // gl_InstanceID), valid for this frame. VK_NULL_HANDLE otherwise.
  VkBuffer shadingRecords = VK_NULL_HANDLE;
  VkDeviceSize shadingRecordsBytes = 0;
};

struct AsServiceDesc {
  // Scratch memory held for builds; 0 = 64 MiB. Queued builds are packed into batches whose scratch fits it;
  // consecutive batches reuse it behind a barrier. A BLAS that alone needs more is built in a batch of its own
  // with transient scratch released after the frame.
  VkDeviceSize scratchBudgetBytes = 0;
  // Triangles one recordPendingWork() call builds at most, to spread a large load over frames; 0 = unlimited.
  // At least one queued build is recorded per call.
  uint64_t maxBuildTrianglesPerCall = 0;
  // Device memory for BLAS storage; 0 = unlimited. When a registration would exceed it, BLASes of released
  // meshes are evicted, least recently used first; never one that a TLAS still in flight references.
  VkDeviceSize blasBudgetBytes = 0;
  VkDeviceSize storageBlockBytes = 0;  // 0 = 32 MiB: size of the blocks BLAS storage is suballocated from
  bool disableCompaction = false;      // false = compact static meshes (skipped where it saves < 2%)
  bool disableTimestamps = false;      // false = time each build batch with timestamp queries
};

// GPU time of one recorded build batch, available frames after it was recorded.
struct BuildBatchTiming {
  uint64_t frame = 0;       // Context::frameIndex() when recorded
  uint32_t blasBuilds = 0;  // builds and refits in the batch
  uint64_t triangles = 0;
  double gpuMs = 0.0;
};

struct AsStats {
  uint32_t meshHandles = 0;        // live handles (registered and not released)
  uint32_t registrations = 0;      // registerMesh calls that succeeded
  uint32_t dedupHits = 0;          // registrations that reused an existing BLAS
  uint32_t blasCount = 0;          // BLASes that exist (built, building or queued)
  uint32_t blasQueued = 0;         // waiting for a build
  uint32_t blasCompacted = 0;      // BLASes whose storage was replaced by a compacted copy
  uint32_t compactionsSkipped = 0; // compaction saved < 2% (lavapipe) so no copy was made
  uint32_t evictions = 0;
  uint64_t triangles = 0;          // triangles over all BLASes
  VkDeviceSize blasBytesBeforeCompaction = 0;  // sum of built sizes of all BLASes
  VkDeviceSize blasBytes = 0;                   // sum of current sizes (after compaction where it happened)
  double bytesPerTriangle = 0.0;                // blasBytes / triangles
  uint32_t storageBlocks = 0;
  VkDeviceSize storageBlockBytes = 0;  // device memory held by the blocks
  VkDeviceSize storageUsedBytes = 0;   // bytes of the blocks in use (aligned BLAS sizes)
  VkDeviceSize scratchBytes = 0;       // persistent scratch memory
  VkDeviceSize tlasBytes = 0;          // TLAS storage, scratch and instance buffers over all frame slots
  uint32_t lastTlasInstances = 0;
  std::vector<BuildBatchTiming> batches;  // the most recent batches with resolved timings (at most 64)
  uint64_t batchTimingsDropped = 0;       // older resolved timings no longer in `batches`
};

class AccelerationStructureService {
 public:
  static Result<std::unique_ptr<AccelerationStructureService>> create(Context& context,
                                                                      const AsServiceDesc& desc = {});
  ~AccelerationStructureService();

  // Validates the description and queues a build, or, on a dedup hit, shares the existing BLAS. Every call
  // returns a handle of its own: registrations that share a BLAS keep their own buffers, attributes and
  // lifetime. Cheap: no GPU work happens until recordPendingWork().
  Result<MeshHandle> registerMesh(const MeshDesc& desc);
  // Ends this registration; its buffers may be freed once the frames in flight are done (a queued build then
  // reads another live registration's buffers). When no registration of a BLAS is left, the BLAS stays
  // cached (a later identical registration revives it) until the memory budget evicts it or the service is
  // destroyed. Further use of the handle is an error.
  Status releaseMesh(MeshHandle mesh);
  // A dynamic mesh's vertices changed: refit its BLAS in the next recordPendingWork().
  Status updateMesh(MeshHandle mesh);

  // Records compaction copies, queued builds and refits into `cmd` within the scratch budget, followed by a
  // barrier that makes them visible to TLAS builds. Returns how many builds are still queued.
  Result<uint32_t> recordPendingWork(VkCommandBuffer cmd);
  // Writes this frame slot's instance buffer and records the TLAS build, followed by a barrier that makes the
  // TLAS readable by ray tracing shaders. Instances of meshes not built yet are skipped (counted). Once per
  // frame (between Context::beginFrame calls); a second call in the same frame is refused.
  Result<TlasInfo> recordTlasBuild(VkCommandBuffer cmd, std::span<const Instance> instances,
                                   const TlasBuildOptions& options = {});

  // State of a mesh's BLAS: true once its build has been recorded (it may then appear in a TLAS).
  Result<bool> isBuilt(MeshHandle mesh) const;
  Result<VkDeviceAddress> blasAddress(MeshHandle mesh) const;
  AsStats stats() const;

  struct Impl;

 private:
  explicit AccelerationStructureService(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace rb
