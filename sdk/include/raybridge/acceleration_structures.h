// Acceleration structures as a service: one BLAS per distinct mesh (content-hash dedup), batched builds
// under a scratch budget, compaction, suballocated storage, a TLAS per frame, LRU eviction under a memory
// budget, explicit eviction for streaming (evictMesh), a queryable state per mesh (MeshState), statistics.
//
// Frame flow, all recorded into the engine's command buffers:
//   ctx.beginFrame();                       // after waiting for the frame slot's fence
//   service.registerMesh(...)               // any time; returns at once, the build is only queued
//   service.updateMesh(dynamicMesh)         // the deforming meshes whose vertices this frame rewrites
//   service.submitDynamicWork(ready)        // async modes: dynamic refits/rebuilds on AsServiceDesc::asyncQueue
//   service.fillTlasWait(wait)              // async modes: a wait for the engine's submission of the TLAS build
//   service.recordPendingWork(cmd);         // compaction copies, queued builds and refits, within budgets
//   service.recordTlasBuild(cmd, instances) // TLAS over the meshes built so far; ready for ray tracing
//
// Dynamic meshes (MeshRole::Dynamic) are refit or rebuilt after updateMesh() as AsServiceDesc::refitPolicy
// decides, either in the frame's command buffer (DynamicBuildMode::InFrame) or on a compute queue the engine hands
// over (the async modes), synchronised by a timeline semaphore the SDK owns and the engine waits on.
//
// Engine buffers are read in place, never copied. Vertex and index buffers must be created with
//   VK_BUFFER_USAGE_SHADER_DEVICE_ADDRESS_BIT | VK_BUFFER_USAGE_ACCELERATION_STRUCTURE_BUILD_INPUT_READ_ONLY_BIT_KHR
// (and memory allocated with VK_MEMORY_ALLOCATE_DEVICE_ADDRESS_BIT). They must stay alive and unchanged
// while their mesh is registered (a dynamic mesh may change between updateMesh() calls).
//
// Thread safety
//   - registerMesh(), releaseMesh(), evictMesh() and meshState() may run concurrently with any other call of this
//     service, from any number of threads (e.g. a streaming thread registering, or evicting under memory pressure,
//     while the render thread records).
//   - Everything else (updateMesh, submitDynamicWork, fillTlasWait, fillVertexReuseWait, recordPendingWork,
//     recordTlasBuild, isBuilt, blasAddress, stats, create and the destructor), and Context::beginFrame() and
//     Context::releaseAfterIdle() of the Context it was created from, stays on one thread at a time: the
//     recording thread. The destructor must not overlap any call.
//   - One internal mutex per service makes this so; the recording calls hold it for their whole duration,
//     so a registration waits for at most one of them (registerMesh validates, hashes the host copies and
//     queries build sizes before taking it).
//   - registerMesh/releaseMesh/evictMesh never touch the Context's deferred-release queue or its frame counter, which
//     beginFrame uses without the lock: the BLASes they evict or free are handed to the Context by the next
//     recording call of this service (so they live until framesInFlight frames after that call), and eviction
//     takes a BLAS as no longer in flight once the Context has released the frame that last traced it.
//   - A handle is safe to use on the recording thread from the moment registerMesh returns it until
//     releaseMesh is called for it; releasing a handle that another thread is passing to recordTlasBuild at
//     the same time is the engine's race (the TLAS build then fails with ErrorCode::StaleHandle or uses it).
//   - The async queue: the SDK submits to AsServiceDesc::asyncQueue only inside submitDynamicWork(), and the
//     engine must not use that VkQueue from another thread during the call (Vulkan's external synchronisation
//     of queues).
#pragma once

#include <raybridge/context.h>

#include <cstdint>
#include <memory>
#include <span>
#include <string>
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
  Dynamic,     // deforming: PREFER_FAST_BUILD + ALLOW_UPDATE, refit or rebuilt after updateMesh(); never compacted
};

// Where the builds and refits of dynamic meshes run, and which pose a frame's TLAS traces.
enum class DynamicBuildMode : uint8_t {
  InFrame = 0,        // default: dynamic BLAS work is recorded by recordPendingWork(cmd), in the frame
  AsyncSameFrame,     // on AsServiceDesc::asyncQueue; this frame's TLAS waits for this frame's builds
  AsyncOneFrameLate,  // the TLAS uses the BLAS built from the previous frame's pose; the graphics queue never
                      // waits for this frame's builds (except a mesh's first, which has no earlier pose)
};
// With no async queue (or one of the engine's own family, e.g. lavapipe's single queue, or one without compute)
// the async modes fall back to recording in recordPendingWork(cmd): the same API and the same semantics
// (one-frame-late still traces the previous pose), reported by AsStats::async == false and
// AsStats::asyncFallbackReason.
//
// Dynamic BLASes are multi-buffered so that a build never writes a BLAS that a frame in flight (or this frame's
// TLAS) reads, with F = Context::framesInFlight(): InFrame and the same-frame fallback keep 1 copy (refit in
// place), AsyncSameFrame F copies, AsyncOneFrameLate F + 1, its fallback 2. Refits form one chain: a refit reads
// the newest copy and writes the next one. A TLAS refit (TlasBuildMode::UpdateIfPossible) is valid only over the
// same BLAS addresses, so with several copies the TLAS is rebuilt in every frame that updated a dynamic mesh.

// How an updated dynamic BLAS is brought up to date.
enum class RefitPolicyKind : uint8_t {
  Adaptive = 0,   // default: refit; rebuild when the refit-quality measure or the refit count says so
  AlwaysRefit,    // refit every update; rebuild only when MeshUpdate::forceRebuild asks
  AlwaysRebuild,  // full build every update, never staggered (the "rebuild every frame" baseline)
};

// Rebuild when the summed AABB surface area of fixed clusters of kRefitClusterTriangles consecutive triangles
// (measured on the GPU by every update of an Adaptive mesh, read back once its work is known done: framesInFlight
// frames later in-frame, usually the next frame async) exceeds this multiple of its value at the last build.
// Refits keep the tree's topology, so triangles that drift apart grow its boxes; by the time the leaves cover half
// as much again, rays pay more than a fast rebuild, which costs about six refits (measured build and refit times:
// docs/benchmarks.md, "animated"). Uniform growth of the mesh (an inflating morph) counts as well; scale that belongs
// to the whole mesh should stay in the instance transform. The clusters follow the index order, which meshes optimised
// for the vertex cache keep spatially coherent; a mesh whose buffers the measure cannot read (not 4-byte
// aligned, or past its 32-bit indexing: over 715,827,882 triangles or 8 GiB of positions) rebuilds by refit count
// only.
constexpr float kDefaultMaxAreaGrowth = 1.5f;
// Rebuild after this many refits in a row even when the measure stays low (two seconds at 60 frames per second):
// clusters of consecutive triangles only approximate the tree's leaves, so drift they do not see is bounded too.
constexpr uint32_t kDefaultMaxRefitsBeforeRebuild = 120;
// Triangles of dynamic BLAS rebuilds per frame (staggered, highest measure first): under a millisecond of
// PREFER_FAST_BUILD work on a current data-centre GPU (docs/benchmarks.md, "animated"), so rebuilds cost a 60 Hz
// frame a small, bounded share.
constexpr uint64_t kDefaultRebuildTrianglesPerFrame = 512ull * 1024;
// Triangles per cluster of the refit-quality measure (and threads per workgroup of its shader).
constexpr uint32_t kRefitClusterTriangles = 64;

// A zero-initialised RefitPolicy is the documented default. Plain value; thread-safe to copy.
struct RefitPolicy {
  RefitPolicyKind kind = RefitPolicyKind::Adaptive;
  float maxAreaGrowth = 0;              // 0 = kDefaultMaxAreaGrowth; otherwise > 1 (Adaptive only)
  uint32_t maxRefitsBeforeRebuild = 0;  // 0 = kDefaultMaxRefitsBeforeRebuild (Adaptive only)
  // 0 = kDefaultRebuildTrianglesPerFrame (Adaptive only). Meshes over the measure wait, still refitting, until
  // their turn; a single mesh larger than the budget is rebuilt alone in a frame of its own.
  uint64_t rebuildTrianglesPerFrame = 0;
};

// An axis-aligned box in a mesh's object space. Plain value. All zero = not given.
struct MeshBounds {
  float min[3] = {0.0f, 0.0f, 0.0f};
  float max[3] = {0.0f, 0.0f, 0.0f};
  bool given() const {
    for (int i = 0; i < 3; ++i)
      if (min[i] != 0.0f || max[i] != 0.0f) return true;
    return false;
  }
};

// Describes one mesh from the engine's own buffers.
struct MeshDesc {
  VkDeviceAddress vertexAddress = 0;   // required: device address of the first vertex position
  VkDeviceSize vertexBufferBytes = 0;  // required: bytes readable from vertexAddress (bounds-checks the counts)
  uint32_t vertexCount = 0;            // required: vertices addressed by this mesh
  VkFormat vertexFormat = VK_FORMAT_UNDEFINED;  // UNDEFINED = VK_FORMAT_R32G32B32_SFLOAT
  uint32_t vertexStride = 0;                    // 0 = the size of vertexFormat (tightly packed positions)
  IndexType indexType = IndexType::Uint32;      // default Uint32
  VkDeviceAddress indexAddress = 0;             // required unless indexType is None
  VkDeviceSize indexBufferBytes = 0;            // required unless indexType is None: bytes readable from indexAddress
  uint32_t triangleCount = 0;                   // required, > 0: triangles read (indexCount / 3, or vertexCount / 3)
  MeshRole role = MeshRole::Static;             // default Static
  bool nonOpaque = false;                       // false = opaque: any-hit shaders are skipped for this geometry
  // Dedup: meshes with equal keys share one BLAS. Dynamic meshes deform independently, so they are deduplicated
  // only by an explicit contentKey. 0 = derive the key: a 64-bit hash of hostVertices and
  // hostIndices when both are given (or hostVertices for non-indexed meshes), else the buffer identity
  // (addresses, counts, format, stride), which shares a BLAS only between registrations of the same range.
  uint64_t contentKey = 0;
  const void* hostVertices = nullptr;  // optional CPU copy, laid out like the GPU buffer (vertexCount*stride)
  const void* hostIndices = nullptr;   // optional CPU copy of the indices (triangleCount*3 indices, any alignment)
  const char* debugName = nullptr;     // optional; appears in error messages (copied: need not outlive the call)
  // Optional object-space box of the vertices (min <= max per axis, finite). HybridEffects restarts the denoisers'
  // history where an instance of the mesh moved, appeared, vanished or deformed: inside its old and new world box,
  // and for shadows and AO where that box can reach (hybrid_effects.h, "Change resets"). All zero = derived from
  // hostVertices when given with R32G32B32_SFLOAT or R32G32B32A32_SFLOAT positions, else unknown: the mesh's changes
  // are then left to the denoisers' anti-lag. A dynamic mesh's box must hold the pose of every update that does not
  // bring its own (MeshUpdate::bounds); a derived one is the registered pose's.
  MeshBounds bounds{};

  // Optional vertex attributes, read (by device address, in place) where reflection rays hit the mesh. The
  // same vertex indexing as the positions. 0 = absent: hits use the triangle's geometric normal and
  // texture coordinate (0, 0). The buffers need VK_BUFFER_USAGE_SHADER_DEVICE_ADDRESS_BIT.
  VkDeviceAddress normalAddress = 0;    // R32G32B32_SFLOAT object-space normals
  uint32_t normalStride = 0;            // 0 = 12
  VkDeviceAddress texcoordAddress = 0;  // R32G32_SFLOAT texture coordinates (glTF convention, v down)
  uint32_t texcoordStride = 0;          // 0 = 8
};

// The state of a registered mesh's BLAS (meshState()), like sokol_gfx's resource states. It belongs to the BLAS, so
// registrations that share one (dedup) share its state. Static meshes go through all four:
//
//   registerMesh -> Queued -> (recordPendingWork records its build) -> Built -> (evictMesh) -> Evicted
//   Evicted -> (a TLAS build, or a registration of equal geometry, references it) -> Queued
//   Queued -> (its build fails) -> Failed -> (a later recordPendingWork retries it) -> Built, or Failed again
//   Queued and Failed go to Evicted by evictMesh too (the build is cancelled, the retries stop).
//
// Dynamic meshes (MeshRole::Dynamic) are only Queued or Built: their builds keep today's behaviour (a failure is
// returned by the call that recorded it and the build stays queued), and evictMesh refuses them.
enum class MeshState : uint8_t {
  // Registered, or re-queued after eviction; the build is not recorded yet. TLAS builds skip its instances
  // (TlasInfo::skippedInstances) until it is Built.
  Queued = 0,
  // Its build is recorded: TLAS builds recorded after it (in the same command buffer or later) reference it.
  Built,
  // Its latest build attempt failed; MeshStatus::error says why: ErrorCode::VulkanError when its BLAS storage or
  // acceleration structure could not be created (the device or host ran out of memory), ErrorCode::OutOfBudget
  // when re-queuing it after eviction found AsServiceDesc::blasBudgetBytes full of registered meshes. Other meshes
  // are not affected: their builds are recorded as if it were not there. The recordPendingWork() call of the
  // attempt returns the error, and every later recordPendingWork() retries it after the builds queued before it
  // (reporting a failed retry the same way) until it is Built; evictMesh() stops the retries, releaseMesh() ends
  // them. TLAS builds skip its instances and count them in TlasInfo::failedInstances.
  Failed,
  // evictMesh() freed its BLAS (the memory returns framesInFlight frames later, when no frame in flight can read
  // it). The registration and its handle stay valid. A TLAS build that references it re-queues its build (Queued;
  // the instance is skipped in that TLAS), or marks it Failed with ErrorCode::OutOfBudget when the budget cannot
  // hold it. A registration of equal geometry (a dedup hit) re-queues it too; when the budget cannot hold it, that
  // registerMesh fails with ErrorCode::OutOfBudget and the mesh stays Evicted.
  Evicted,
};

// What meshState() reports. Plain value; thread-safe to copy.
struct MeshStatus {
  MeshState state = MeshState::Queued;
  // MeshState::Failed: the error of the latest failed attempt (its code, the failing VkResult for
  // ErrorCode::VulkanError, and a message naming the mesh, the failed call and what to do). Otherwise
  // ErrorCode::Ok with an empty message.
  Error error;
};

// One TLAS instance. Instance{} is the identity transform, visible to every ray mask.
struct Instance {
  MeshHandle mesh{};  // required
  // Row-major 3x4 object-to-world matrix (the layout of VkTransformMatrixKHR). Default identity.
  float transform[12] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0};
  uint32_t customIndex = 0;  // 24 bits; gl_InstanceCustomIndexEXT
  uint8_t mask = 0xFF;       // default: visible to all rays
  uint32_t sbtRecordOffset = 0;
  VkGeometryInstanceFlagsKHR flags = 0;
  // Index into the MaterialTable (MaterialTable::setMaterials); read by passes that shade hits and by the
  // alpha test of non-opaque meshes.
  uint32_t material = 0;

  // Sets `transform` from a column-major 4x4 matrix (GLM's and most engines' layout); the last row is ignored.
  void setTransformColumnMajor(const float m[16]) {
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 4; ++c) transform[r * 4 + c] = m[c * 4 + r];
  }
};

enum class TlasBuildMode : uint8_t {
  Adaptive = 0,      // default: refit the previous frame's TLAS when UpdateIfPossible could, and rebuild instead
                     // when the instances drifted apart since the last rebuild (TlasBuildOptions::maxAreaGrowth)
                     // or after maxRefits refits in a row: a fifth of Rebuild's cost a frame, tracing as fast
                     // (docs/performance.md, "TLAS refits")
  Rebuild,           // a full build every frame (for a list whose instances all jump every frame)
  UpdateIfPossible,  // refit the previous frame's TLAS when the instance list has the same meshes and count
                     // (and BLAS copies: see DynamicBuildMode) and it was built with the same preference; never
                     // rebuilds on motion, so a TLAS whose instances scatter traces slower and slower
};

// TlasBuildMode::Adaptive rebuilds when the summed surface area of groups of instances that were neighbours at
// the last rebuild (about 16 per cell of a uniform grid over their origins; each instance a cube of half a cell
// around its origin under its rotation and scale) exceeds this multiple of its value then. A refit keeps the
// tree's topology, so neighbours that drift apart, spin or grow enlarge its boxes; a group that moves together
// does not. Measured on the host from the instance transforms (the SDK has no mesh bounds there: the cell stands
// for an instance's size).
// The value and the trace cost of refitted TLASes: docs/performance.md, "TLAS refits".
constexpr float kDefaultTlasMaxAreaGrowth = 1.5f;
// TlasBuildMode::Adaptive rebuilds after this many refits in a row even when the measure stays low (one second at
// 60 frames per second): a rebuild every 60 frames costs a 60th of its time per frame.
constexpr uint32_t kDefaultTlasMaxRefits = 60;

// Where the TLAS build reads the instance list from. The SDK writes it on the host into host-visible memory; on a
// discrete GPU that memory sits across the bus, and a build that reads it there pays the bus's latency for every
// instance (docs/performance.md, "TLAS").
enum class TlasInstanceUpload : uint8_t {
  Auto = 0,      // default: CopyToDevice where host-visible memory is not device-local, else ReadInPlace
  ReadInPlace,   // the build reads the host-visible buffer directly (no copy, no device-local buffer)
  CopyToDevice,  // vkCmdCopyBuffer into a device-local buffer first (one more buffer per frame slot)
};

// The build's trade-off for the TLAS (a BLAS of a static mesh is always built for fast trace).
enum class TlasBuildPreference : uint8_t {
  FastTrace = 0,  // default: VK_BUILD_ACCELERATION_STRUCTURE_PREFER_FAST_TRACE_BIT_KHR
  FastBuild,      // VK_BUILD_ACCELERATION_STRUCTURE_PREFER_FAST_BUILD_BIT_KHR: for very many instances per frame
};

struct TlasBuildOptions {
  TlasBuildMode mode = TlasBuildMode::Adaptive;  // the zero value, as HybridEffectsDesc::tlasMode's default
  TlasInstanceUpload instanceUpload = TlasInstanceUpload::Auto;
  TlasBuildPreference preference = TlasBuildPreference::FastTrace;
  // Subtracted (in double precision) from every instance's translation, so a camera-relative TLAS keeps full
  // float precision far from the world origin. Default 0: world space.
  double originOffset[3] = {0.0, 0.0, 0.0};
  // TlasBuildMode::Adaptive only: 0 = kDefaultTlasMaxAreaGrowth, otherwise > 1.
  float maxAreaGrowth = 0.0f;
  // TlasBuildMode::Adaptive only: 0 = kDefaultTlasMaxRefits; 1 rebuilds every other frame.
  uint32_t maxRefits = 0;
  // Also write, per TLAS instance, where its vertex data and material are (TlasInfo::shadingRecords), for
  // passes that shade the surfaces rays hit (reflections) or alpha-test them (any pass, when a mesh is
  // non-opaque). false = no such buffer is allocated.
  bool writeShadingRecords = false;
};

struct TlasInfo {
  VkAccelerationStructureKHR tlas = VK_NULL_HANDLE;
  VkDeviceAddress address = 0;
  uint32_t instanceCount = 0;     // instances written into the TLAS
  uint32_t skippedInstances = 0;  // instances whose mesh has no built BLAS yet (MeshState::Queued, Evicted)
  uint32_t failedInstances = 0;   // instances left out because their mesh is MeshState::Failed (see meshState())
  // Instances written whose geometry runs any-hit shaders (MeshDesc::nonOpaque, or forced by
  // VK_GEOMETRY_INSTANCE_FORCE_NO_OPAQUE_BIT_KHR). 0 = the passes keep the opaque fast path.
  uint32_t nonOpaqueInstances = 0;
  bool updated = false;  // true if refit rather than rebuilt
  // TlasBuildMode::Adaptive: the measure that decided this frame (1 after a rebuild), and the refits since
  // the last rebuild, this one included (0 after a rebuild). Other modes: 0 and 0.
  float areaGrowth = 0.0f;
  uint32_t refitsSinceRebuild = 0;
  double originOffset[3] = {0.0, 0.0, 0.0};  // TlasBuildOptions::originOffset it was built with
  // With TlasBuildOptions::writeShadingRecords: a storage buffer of one record per TLAS instance (indexed by
  // gl_InstanceID), valid for this frame. VK_NULL_HANDLE otherwise.
  VkBuffer shadingRecords = VK_NULL_HANDLE;
  VkDeviceSize shadingRecordsBytes = 0;
};

// AsServiceDesc::releasedCacheBytes when left 0: the released BLASes a streaming engine re-registers soon (a
// level's props, a character's LODs) stay, and a level's worth of released geometry does not.
inline constexpr VkDeviceSize kDefaultReleasedCacheBytes = 16ull << 20;

// Recording calls (recordPendingWork) over which the build scratch held is measured: at the end of each such
// window it is released if no call of the window needed more than a quarter of it (the next build creates it again
// at its need). About a second at 60 frames a second: builds come in bursts (a level's load, a streamed area),
// refits every frame. So 2 x kScratchWindowCalls calls without builds leave no scratch held.
inline constexpr uint32_t kScratchWindowCalls = 64;

struct AsServiceDesc {
  // Build scratch at most; 0 = 64 MiB. Queued builds are packed into batches whose scratch fits it; consecutive
  // batches reuse it behind a barrier. A BLAS that alone needs more is built in a batch of its own with transient
  // scratch released after the frame. The scratch held grows to what the batches need (doubling, up to this), and
  // is freed when a window of kScratchWindowCalls recording calls needed at most a quarter of it.
  VkDeviceSize scratchBudgetBytes = 0;
  // Triangles one recordPendingWork() call builds at most, to spread a large load over frames; 0 = unlimited.
  // At least one queued build is recorded per call. First builds of dynamic meshes count too (in the async modes
  // against a cap of their own per submitDynamicWork() call); their rebuilds follow RefitPolicy instead.
  uint64_t maxBuildTrianglesPerCall = 0;
  // Device memory for BLAS storage; 0 = unlimited. When a registration would exceed it, BLASes of released
  // meshes are evicted, least recently used first; never one that a TLAS still in flight references.
  VkDeviceSize blasBudgetBytes = 0;
  // The largest block BLAS storage is suballocated from; 0 = 32 MiB. The blocks grow with the content: the first
  // is 256 KiB, each new one as large as those held together, up to this; a BLAS larger than it gets a block of its
  // own size. An empty block is freed.
  VkDeviceSize storageBlockBytes = 0;
  // BLAS storage of meshes with no registration left that the service keeps, so that a later registration of equal
  // geometry revives it without a build. Beyond it the least recently released are freed (once no frame in flight
  // reads them), so the memory held comes back down when the content is released. 0 = kDefaultReleasedCacheBytes.
  // blasBudgetBytes evicts them too, when a registration needs the room.
  VkDeviceSize releasedCacheBytes = 0;
  bool disableReleasedCache = false;  // true = free a BLAS once its last registration is released
  bool disableCompaction = false;     // false = compact static meshes (skipped where it saves < 2%)
  bool disableTimestamps = false;     // false = time each build batch with timestamp queries

  // A compute queue the engine hands over for the async dynamic modes; VK_NULL_HANDLE = none (the async modes
  // fall back to InFrame recording, see DynamicBuildMode). Used only inside submitDynamicWork(); the engine
  // must not use it concurrently with that call. Ignored by DynamicBuildMode::InFrame.
  VkQueue asyncQueue = VK_NULL_HANDLE;
  // asyncQueue's family (ignored without asyncQueue). The engine's buffers that dynamic meshes read (vertices,
  // indices) must be VK_SHARING_MODE_CONCURRENT over it and ContextDesc::mainQueueFamily; equal to the main
  // family, or a family without VK_QUEUE_COMPUTE_BIT, means the fallback.
  uint32_t asyncQueueFamily = 0;
  DynamicBuildMode dynamicMode = DynamicBuildMode::InFrame;  // default InFrame
  RefitPolicy refitPolicy{};                                 // zero = the defaults above
};

// What changed about a dynamic mesh (updateMesh). Plain value; thread-safe to copy.
struct MeshUpdate {
  // nullptr = same buffers and counts, new vertex contents (refit, or rebuild as the policy decides).
  // Non-null = the mesh's new description (buffers may move); a changed vertexCount or triangleCount (or vertex
  // format, index type, opacity) needs forceRebuild, else updateMesh fails naming the old and new values.
  const MeshDesc* desc = nullptr;
  bool forceRebuild = false;  // rebuild in the next dynamic work, outside the staggering budget
  // The new pose's object-space box (the one an engine culls a skinned mesh with); all zero = the registered one
  // (or desc's). See MeshDesc::bounds.
  MeshBounds bounds{};
};

// What made this frame's deformed vertex buffers ready: a value of the engine's timeline semaphore, signalled
// by a submission on the main queue made after the previous frame's main submission. Plain value.
struct AsyncBuildWait {
  VkSemaphore semaphore = VK_NULL_HANDLE;  // timeline semaphore; VK_NULL_HANDLE = nothing to wait for
  uint64_t value = 0;
};

// GPU time of one recorded build batch, available frames after it was recorded.
struct BuildBatchTiming {
  uint64_t frame = 0;       // Context::frameIndex() when recorded
  uint32_t blasBuilds = 0;  // builds and refits in the batch
  uint64_t triangles = 0;
  double gpuMs = 0.0;
};

struct AsStats {
  uint32_t meshHandles = 0;                    // live handles (registered and not released)
  uint32_t nonOpaqueMeshes = 0;                // live handles registered with MeshDesc::nonOpaque
  uint32_t registrations = 0;                  // registerMesh calls that succeeded
  uint32_t dedupHits = 0;                      // registrations that reused an existing BLAS
  uint32_t blasCount = 0;                      // BLASes that exist (built, building or queued; not Failed or Evicted)
  uint32_t blasQueued = 0;                     // waiting for a build
  uint32_t blasFailed = 0;                     // BLASes in MeshState::Failed (waiting for their retry; hold no storage)
  uint32_t blasEvicted = 0;                    // BLASes in MeshState::Evicted (registered, hold no storage nor budget)
  uint32_t blasCompacted = 0;                  // BLASes whose storage was replaced by a compacted copy
  uint32_t compactionsSkipped = 0;             // compaction saved < 2% (lavapipe) so no copy was made
  uint32_t evictions = 0;                      // cached BLASes (no registration left) freed by the budget or
                                               // releasedCacheBytes, least recently released first
  uint32_t meshEvictions = 0;                  // BLASes freed by evictMesh() (cumulative)
  VkDeviceSize evictedBlasBytes = 0;           // their sizes then (cumulative); no longer in blasBytes, and out of
                                               // storageUsedBytes once the frames in flight are done
  uint64_t triangles = 0;                      // triangles over all BLASes
  VkDeviceSize blasBytesBeforeCompaction = 0;  // sum of built sizes of all BLASes
  VkDeviceSize blasBytes = 0;                  // sum of current sizes (after compaction where it happened;
                                               // every copy of a dynamic BLAS)
  double bytesPerTriangle = 0.0;               // blasBytes / triangles
  uint32_t storageBlocks = 0;
  VkDeviceSize storageBlockBytes = 0;  // device memory held by the blocks
  VkDeviceSize storageUsedBytes = 0;   // bytes of the blocks in use (aligned BLAS sizes)
  VkDeviceSize scratchBytes = 0;       // persistent scratch memory
  VkDeviceSize tlasBytes = 0;          // TLAS storage, scratch and instance buffers over all frame slots
  uint32_t lastTlasInstances = 0;
  uint64_t tlasBuilds = 0;                // TLAS full builds recorded
  uint64_t tlasRefits = 0;                // TLAS refits recorded (UpdateIfPossible, Adaptive)
  std::vector<BuildBatchTiming> batches;  // the most recent batches with resolved timings (at most 64); an
                                          // async submission is one batch
  uint64_t batchTimingsDropped = 0;       // older resolved timings no longer in `batches`

  // Dynamic meshes (cumulative unless said).
  uint64_t refits = 0;                     // dynamic BLAS refits recorded
  uint64_t rebuilds = 0;                   // full rebuilds of already built dynamic BLASes recorded
  uint64_t lastFrameRefitTriangles = 0;    // of the latest frame's dynamic work
  uint64_t lastFrameRebuildTriangles = 0;  // of the latest frame's dynamic work (rebuilds, not first builds)
  bool async = false;                      // dynamic work runs on the async queue
  uint32_t asyncQueueFamily = UINT32_MAX;  // its family, when async
  std::string asyncFallbackReason;         // why not async, when an async mode was asked for; else empty
  uint32_t staleBlas = 0;                  // instances of the last TLAS traced with a pose older than the
                                           // mesh's newest update (one-frame-late mode)
  double lastAsyncGpuMs = 0.0;             // GPU time of the latest resolved async submission
  VkDeviceSize dynamicBlasBytes = 0;       // storage of dynamic BLASes, all copies
};

class AccelerationStructureService {
 public:
  static Result<std::unique_ptr<AccelerationStructureService>> create(Context& context, const AsServiceDesc& desc = {});
  // Never waits. Contract, as for the Context: the GPU is done with the engine's frames that used this service
  // and with the SDK's submissions on the async queue (the engine's vkDeviceWaitIdle, or a wait on that queue
  // or on the SDK's timeline), and the engine has submitted the signals of the `ready` values it passed.
  // Unlike the passes it does not defer: it destroys its TLASes and BLASes at once, and it releases every
  // object retired to the context so far (its retired BLASes live in its storage blocks), those of destroyed
  // passes included. Destroy it at shutdown (or after a wait-idle), not in the middle of a run.
  ~AccelerationStructureService();

  // Validates the description and queues a build, or, on a dedup hit, shares the existing BLAS. Every call
  // returns a handle of its own: registrations that share a BLAS keep their own buffers, attributes and
  // lifetime. Cheap: no GPU work happens until recordPendingWork().
  Result<MeshHandle> registerMesh(const MeshDesc& desc);
  // Ends this registration; its buffers may be freed once the frames in flight are done (a queued build then
  // reads another live registration's buffers). When no registration of a BLAS is left, the BLAS stays
  // cached (a later identical registration revives it) until AsServiceDesc::releasedCacheBytes or the memory
  // budget evicts it, or the service is destroyed. Further use of the handle is an error.
  Status releaseMesh(MeshHandle mesh);
  // A dynamic mesh's vertices changed (or, with update.desc, its buffers): refit or rebuild its BLAS, as the
  // policy decides, in the frame's dynamic work (submitDynamicWork() in the async modes, else the next
  // recordPendingWork()). Call it after the frame's beginFrame and before that work. A BLAS shared by several
  // registrations (one contentKey) is updated for all of them.
  Status updateMesh(MeshHandle mesh, const MeshUpdate& update = {});

  // Once per frame, after the updateMesh calls of the frame and before recordPendingWork/recordTlasBuild.
  // Async modes: records the dynamic BLAS builds, refits and rebuilds into the SDK's own command buffer and
  // submits it on the async queue, waiting on `ready` (stages ACCELERATION_STRUCTURE_BUILD | COMPUTE_SHADER)
  // and signalling the SDK's timeline semaphore; nothing is submitted when there is no dynamic work. InFrame mode
  // and the fallback: does nothing (recordPendingWork records the work). A second call in a frame that already
  // submitted work is refused (a second write could hit the copy this frame's TLAS reads).
  Status submitDynamicWork(const AsyncBuildWait& ready = {});
  // The wait the engine's submission of the TLAS build and the passes needs: the SDK's timeline semaphore at the
  // value of the submission that wrote the BLAS copies this frame's TLAS will use (same-frame: this frame's;
  // one-frame-late: the newest of an earlier frame, or this frame's for a mesh's first build), stage
  // ACCELERATION_STRUCTURE_BUILD | RAY_TRACING_SHADER | COMPUTE_SHADER. Returns false and leaves `out` alone
  // when none is needed (InFrame, the fallback, or no dynamic BLAS written on the async queue).
  bool fillTlasWait(VkSemaphoreSubmitInfo& out) const;
  // The wait the engine's next write to the vertex buffers of dynamic meshes needs: the value of the latest
  // submission that read them, stage ALL_COMMANDS. Returns false and leaves `out` alone when none is needed.
  bool fillVertexReuseWait(VkSemaphoreSubmitInfo& out) const;
  // The four calls above in one, for the usual frame: updateMesh() for each of `meshes` (with poseBounds[i] as its
  // MeshUpdate::bounds when given: one per mesh, or empty), submitDynamicWork(ready), then the waits appended to the
  // engine's lists (either may be nullptr when the engine has no such list).
  Status updateDynamicMeshes(std::span<const MeshHandle> meshes, const AsyncBuildWait& ready,
                             std::vector<VkSemaphoreSubmitInfo>* tlasWaits,
                             std::vector<VkSemaphoreSubmitInfo>* vertexReuseWaits,
                             std::span<const MeshBounds> poseBounds = {});

  // Records compaction copies and queued builds into `cmd` within the scratch budget, followed by a barrier that
  // makes them visible to TLAS builds; in DynamicBuildMode::InFrame and the async fallback also the frame's
  // dynamic work (first builds, refits, rebuilds and their measure, once per frame), which binds a compute
  // pipeline and push constants in `cmd`. Returns how many builds are still queued. On an error the builds it could
  // not record stay queued for the next call; a failed read of earlier builds' queries (a lost device) is returned
  // too, naming vkGetQueryPoolResults. A build that fails for its own mesh (its storage or acceleration structure
  // could not be created) makes that mesh MeshState::Failed and does not stop the others: the call records them and
  // then returns the first such error, naming the mesh. Either way, submit `cmd`: what it holds is valid.
  Result<uint32_t> recordPendingWork(VkCommandBuffer cmd);
  // Writes this frame slot's instance buffer and records the TLAS build, followed by a barrier that makes the
  // TLAS readable by ray tracing shaders. Instances of meshes not built yet are skipped (counted): Queued ones in
  // TlasInfo::skippedInstances, Failed ones in TlasInfo::failedInstances (the frame renders without them rather
  // than fail; recordPendingWork returned their error, meshState() still has it). An Evicted mesh is re-queued
  // (skipped in this TLAS, built by the next recordPendingWork) or, when the budget cannot hold it, made Failed. Once
  // per frame (between Context::beginFrame calls); a second call in the same frame is refused.
  Result<TlasInfo> recordTlasBuild(VkCommandBuffer cmd, std::span<const Instance> instances,
                                   const TlasBuildOptions& options = {});

  // Frees the BLAS of a static mesh to make room (streaming under memory pressure) and keeps its registration:
  // MeshState::Evicted. Its storage is handed to the Context's deferred release by the next recording call and
  // returns framesInFlight frames after it, so frames in flight that trace it stay valid; it leaves the budget
  // (AsServiceDesc::blasBudgetBytes) and AsStats::blasBytes at once.
  // Every registration that shares the BLAS (dedup) is evicted with it. A queued or failed build is cancelled.
  // Evicting an Evicted mesh does nothing. A TLAS build that references an Evicted mesh re-queues its build (see
  // MeshState::Evicted). Errors: a stale or null handle (StaleHandle, InvalidArgument), a dynamic mesh
  // (InvalidArgument: release it instead). Thread safety: as registerMesh.
  Status evictMesh(MeshHandle mesh);
  // The state of a mesh's BLAS and, when Failed, the error of the failed build (see MeshState). A stale handle is
  // ErrorCode::StaleHandle, the null handle InvalidArgument. Thread safety: as registerMesh (any thread); the state
  // can change as soon as it returns, by the recording thread's calls or by evictMesh.
  Result<MeshStatus> meshState(MeshHandle mesh) const;
  // meshState(mesh) == MeshState::Built: its build has been recorded (it may then appear in a TLAS).
  Result<bool> isBuilt(MeshHandle mesh) const;
  // For a dynamic mesh: the newest copy (see DynamicBuildMode), which changes with every update.
  Result<VkDeviceAddress> blasAddress(MeshHandle mesh) const;
  AsStats stats() const;
  // Live registrations with MeshDesc::nonOpaque (what AsStats::nonOpaqueMeshes reports), without resolving the
  // rest of the statistics: a TLAS needs shading records for alpha testing when it is non-zero.
  uint32_t nonOpaqueMeshCount() const;
  // What HybridEffects' change resets read per instance (out.size() == instances.size()): the mesh's box and how
  // many times it was updated. A stale or null handle gives bounds.given() == false. Thread safety: as meshState().
  struct MeshChange {
    MeshBounds bounds{};  // object space; not given() = unknown
    uint64_t poses = 0;   // updateMesh calls so far (dynamic meshes)
    // bounds is the latest update's own MeshUpdate::bounds: a new pose with an unchanged box is read as the same
    // pose (an engine that updates a paused character every frame). Else any update is read as a deformation.
    bool poseBounds = false;
  };
  void meshChanges(std::span<const Instance> instances, std::span<MeshChange> out) const;

  struct Impl;

 private:
  explicit AccelerationStructureService(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace rb
