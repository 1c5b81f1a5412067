// The Raybridge context adopts the engine's Vulkan device. It never creates a device, never submits work and
// never waits on the engine's queues; everything that does GPU work records into a command buffer the engine
// passes in.
//
// Lifetimes: the SDK owns them. Destroying a pass (ShadowPass, AoPass, ReflectionPass, PrimaryRayPass) or a
// Denoiser, or replacing one of its resources (a resize, a new material table), never destroys Vulkan objects
// at once: they are retired to the context, which destroys them and frees their memory once the frames in
// flight that may use them are done (Context::beginFrame's contract, or releaseAfterIdle()). So the engine
// may destroy a pass right after recording it, with no wait-idle and no retire list of its own; memoryStats()
// drops when the memory is actually freed. Exceptions: ~AccelerationStructureService and ~Context, whose
// contract is that the GPU is done (see there).
//
// Failures: a call whose Vulkan call fails (out of memory, say) returns ErrorCode::VulkanError naming that call
// and its VkResult, and leaves its object consistent: the engine destroys it (nothing leaks) or calls again (the
// next frame), which picks up where the failure stopped. A lost device shows as the error of the next call that reads
// query results (VK_ERROR_DEVICE_LOST from vkGetQueryPoolResults: a pass's or Denoiser's record(),
// recordPendingWork()); the statistics then go without timings, and destruction stays clean (docs/reliability.md).
//
// Thread safety: a Context is externally synchronised. Calls on one context (and on the services and passes
// created from it) must not overlap; distinct contexts may be used from distinct threads.
#pragma once

#include <raybridge/result.h>

#include <cstdint>
#include <memory>
#include <span>
#include <string>

namespace rb {

namespace internal {
struct ContextAccess;  // the SDK's own way in (sdk/src/core/context_access.h); not part of the API
}

// The Vulkan API version Raybridge needs: the engine's VkApplicationInfo::apiVersion and the device's.
inline constexpr uint32_t kMinimumApiVersion = VK_API_VERSION_1_2;

// What the engine hands over. A zero-initialised ContextDesc is invalid only because the four handles below
// are required; every other field's zero value is a documented default. Fill it with designated initialisers
// (the fields are in this order):
//   rb::ContextDesc desc{.instance = instance, .physicalDevice = gpu, .device = device,
//                        .getInstanceProcAddr = vkGetInstanceProcAddr, .framesInFlight = 2,
//                        .mainQueueFamily = graphicsFamily, .apiVersion = VK_API_VERSION_1_3};
struct ContextDesc {
  VkInstance instance = VK_NULL_HANDLE;                        // required
  VkPhysicalDevice physicalDevice = VK_NULL_HANDLE;            // required
  VkDevice device = VK_NULL_HANDLE;                            // required; see requiredDeviceExtensions()
  PFN_vkGetInstanceProcAddr getInstanceProcAddr = nullptr;     // required; every Vulkan function is loaded from it
  uint32_t framesInFlight = 0;                                 // 0 = 2; at most 8
  const VkAllocationCallbacks* allocationCallbacks = nullptr;  // nullptr = the driver's allocator
  // Family of the engine's queue that executes Raybridge's recordings (for its timestamp bits). Refits of
  // deforming meshes are recorded into the same command buffers as everything else, unless the engine hands
  // an AccelerationStructureService a compute queue of another family (AsServiceDesc::asyncQueue).
  uint32_t mainQueueFamily = 0;
  // Whether the engine enabled VK_NV_ray_tracing_invocation_reorder and its feature rayTracingInvocationReorder
  // (OptionalFeatures::invocationReorder) on `device`; the SDK cannot query what a device enabled, so it takes
  // the engine's word. false (default) = the SDK never reorders. true = the ReflectionPass may reorder its hit
  // shading (opt-in: ReflectionSettings::invocationReorder); Context::create fails with MissingExtension or
  // MissingFeature when the physical device does not support it (check supportsInvocationReorder() first).
  bool invocationReorderEnabled = false;
  // The VkApplicationInfo::apiVersion the engine created its instance with. 0 = not stated: Context::create then
  // infers a version below 1.2 from the Vulkan 1.2 features all reading as unsupported. Below
  // kMinimumApiVersion, Context::create fails with ErrorCode::UnsupportedApiVersion (the Vulkan 1.2 functions and
  // features Raybridge uses do not exist for such an instance, whatever the device supports).
  uint32_t apiVersion = 0;
};

// Device extensions the engine must enable on its VkDevice for Raybridge (Vulkan 1.2 or newer).
std::span<const char* const> requiredDeviceExtensions();

// Feature structures the engine must chain into VkDeviceCreateInfo::pNext with every listed feature enabled
// (Vulkan 1.2 features including timelineSemaphore; Raybridge needs no synchronization2).
// Fill one with enableRequiredFeatures() and link `chainHead()` into the engine's own chain, e.g.
//   rb::RequiredFeatures f; f.link(&engineFeatures2); createInfo.pNext = f.chainHead();
struct RequiredFeatures {
  VkPhysicalDeviceVulkan12Features vulkan12{};
  VkPhysicalDeviceAccelerationStructureFeaturesKHR accelerationStructure{};
  VkPhysicalDeviceRayTracingPipelineFeaturesKHR rayTracingPipeline{};
  RequiredFeatures();  // sets sTypes, chains the structs and turns every required feature on
  // Appends `next` after the last Raybridge struct and returns the head of the chain.
  void* link(void* next);
  void* chainHead() { return &vulkan12; }
  // For engines that fill their own VkPhysicalDeviceVulkan12Features: OR Raybridge's 1.2 features into it,
  // and chain only the extension structs (acceleration structure -> ray tracing pipeline -> `next`).
  void mergeVulkan12Into(VkPhysicalDeviceVulkan12Features& engineFeatures) const;
  void* extensionChain(void* next) {
    rayTracingPipeline.pNext = next;
    return &accelerationStructure;
  }
};

// Optional: shader execution reordering (VK_NV_ray_tracing_invocation_reorder). Where the physical device supports
// it (supportsInvocationReorder), the engine may add kInvocationReorderExtension to its device extensions, chain
// OptionalFeatures::invocationReorder into VkDeviceCreateInfo::pNext and set ContextDesc::invocationReorderEnabled.
// The ReflectionPass then sorts its hits by instance before shading them (divergent materials per lane).
inline constexpr const char* kInvocationReorderExtension = VK_NV_RAY_TRACING_INVOCATION_REORDER_EXTENSION_NAME;
// Whether `physicalDevice` has the extension and its feature rayTracingInvocationReorder. Instance-level
// queries only (vkEnumerateDeviceExtensionProperties, vkGetPhysicalDeviceFeatures2 from `getInstanceProcAddr`):
// call it before creating the device. false when a query function cannot be loaded.
bool supportsInvocationReorder(VkInstance instance, VkPhysicalDevice physicalDevice,
                               PFN_vkGetInstanceProcAddr getInstanceProcAddr);

// Feature structures of the optional extensions above, each with its features turned on and pNext null: chain one
// (set its pNext) only when its extension is enabled too.
struct OptionalFeatures {
  VkPhysicalDeviceRayTracingInvocationReorderFeaturesNV invocationReorder{};
  OptionalFeatures();  // sets sTypes and turns every feature on
};

// Device properties Raybridge reads once at creation.
struct DeviceInfo {
  std::string deviceName;
  std::string driverName;  // e.g. "llvmpipe" or "NVIDIA"
  std::string driverInfo;  // driver version string
  uint32_t apiVersion = 0;
  uint32_t vendorId = 0;
  bool isCpu = false;  // a software rasteriser such as lavapipe
  uint32_t shaderGroupHandleSize = 0;
  uint32_t shaderGroupHandleAlignment = 0;
  uint32_t shaderGroupBaseAlignment = 0;
  uint32_t maxRayRecursionDepth = 0;
  uint32_t minAccelerationStructureScratchOffsetAlignment = 0;
  uint64_t maxPrimitiveCount = 0;
  uint64_t maxInstanceCount = 0;
  float timestampPeriodNs = 0.0f;   // nanoseconds per timestamp tick
  uint32_t timestampValidBits = 0;  // of the queue family executing Raybridge's work
  bool timestampsSupported = false;
  // ContextDesc::invocationReorderEnabled, checked against the device: the ReflectionPass may reorder.
  bool invocationReorder = false;
  // With invocationReorder: whether the driver says it actually reorders (VkPhysicalDeviceRayTracingInvocation-
  // ReorderPropertiesNV::rayTracingInvocationReorderReorderingHint is REORDER); false = the calls are accepted
  // but threads stay where they are, so reordering costs a little and gains nothing.
  bool invocationReorderReorders = false;
  // Ticks from `start` to `end`, modulo the counter's valid bits.
  uint64_t timestampTicks(uint64_t start, uint64_t end) const {
    uint64_t mask = timestampValidBits >= 64 ? ~0ull : (1ull << timestampValidBits) - 1;
    return (end - start) & mask;
  }
};

// Device memory Raybridge holds, by what it is for. Buffers no enabled effect reads are never allocated, so a
// disabled effect shows zero bytes in its category (once its destroyed pass's memory has been released).
// Retired memory still counts until it is freed.
enum class MemoryCategory : uint8_t {
  BlasStorage = 0,  // suballocation blocks holding BLASes
  Scratch,          // build scratch memory
  Tlas,             // TLAS storage, scratch and instance buffers
  ShaderTables,     // shader binding tables and pipeline constants
  PassImages,       // images owned by the effect passes (history, intermediate results)
  PassBuffers,      // other buffers owned by the effect passes
  Count
};
const char* toString(MemoryCategory category);

struct MemoryStats {
  VkDeviceSize bytes[static_cast<size_t>(MemoryCategory::Count)] = {};
  uint32_t allocations = 0;  // live VkDeviceMemory objects
  VkDeviceSize total() const {
    VkDeviceSize sum = 0;
    for (VkDeviceSize b : bytes) sum += b;
    return sum;
  }
  VkDeviceSize of(MemoryCategory c) const { return bytes[static_cast<size_t>(c)]; }
};

class Context {
 public:
  static Result<std::unique_ptr<Context>> create(const ContextDesc& desc);
  // Contract: every service and pass created from this context is destroyed already, and the GPU has
  // finished every command buffer Raybridge recorded into (the engine's wait-idle at shutdown, or its fences
  // of every frame in flight). Objects still retired then (destroyed passes, replaced resources) are destroyed
  // at once; the context never waits for the GPU itself.
  ~Context();
  Context(const Context&) = delete;
  Context& operator=(const Context&) = delete;

  // Marks the start of a new frame. Contract: when the engine calls this, the GPU has finished all work the
  // engine submitted before its previous `framesInFlight` calls to beginFrame (the usual wait on the frame
  // slot's fence). Objects retired that long ago are destroyed here: what was retired after beginFrame
  // number N is destroyed by beginFrame number N + framesInFlight.
  void beginFrame();
  // The engine guarantees the device is idle (after vkDeviceWaitIdle, say): every deferred release happens now,
  // and every query (build timings, compacted sizes, pass statistics) recorded so far can be read.
  void releaseAfterIdle();

  uint64_t frameIndex() const;  // number of beginFrame calls so far
  uint32_t framesInFlight() const;
  const DeviceInfo& deviceInfo() const;
  VkDevice device() const;
  VkPhysicalDevice physicalDevice() const;
  MemoryStats memoryStats() const;

  struct Impl;  // opaque

 private:
  friend struct internal::ContextAccess;
  explicit Context(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace rb
