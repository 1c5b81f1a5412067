#include "failure_injection.h"

#include <cstdio>
#include <cstring>
#include <mutex>
#include <type_traits>
#include <unordered_map>

namespace rbtest {

namespace {

constexpr uint64_t kPoison = 0xBAD0BAD0BAD0BAD0ull;

template <typename H>
uint64_t key(H h) {
  if constexpr (std::is_pointer_v<H>) {
    return uint64_t(reinterpret_cast<uintptr_t>(h));
  } else {
    return uint64_t(h);
  }
}

template <typename H>
H poison() {
  if constexpr (std::is_pointer_v<H>) {
    return reinterpret_cast<H>(uintptr_t(kPoison));
  } else {
    return H(kPoison);
  }
}

std::string hex(uint64_t v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "0x%llx", static_cast<unsigned long long>(v));
  return buf;
}

// Every function the injector wraps.
#define RBTEST_WRAPPED(X)                 \
  X(vkAllocateMemory)                     \
  X(vkFreeMemory)                         \
  X(vkMapMemory)                          \
  X(vkBindBufferMemory)                   \
  X(vkBindImageMemory)                    \
  X(vkCreateBuffer)                       \
  X(vkDestroyBuffer)                      \
  X(vkCreateImage)                        \
  X(vkDestroyImage)                       \
  X(vkCreateImageView)                    \
  X(vkDestroyImageView)                   \
  X(vkCreateSampler)                      \
  X(vkDestroySampler)                     \
  X(vkCreateQueryPool)                    \
  X(vkDestroyQueryPool)                   \
  X(vkGetQueryPoolResults)                \
  X(vkCreateShaderModule)                 \
  X(vkDestroyShaderModule)                \
  X(vkCreatePipelineLayout)               \
  X(vkDestroyPipelineLayout)              \
  X(vkCreateComputePipelines)             \
  X(vkCreateRayTracingPipelinesKHR)       \
  X(vkGetRayTracingShaderGroupHandlesKHR) \
  X(vkDestroyPipeline)                    \
  X(vkCreateDescriptorSetLayout)          \
  X(vkDestroyDescriptorSetLayout)         \
  X(vkCreateDescriptorPool)               \
  X(vkDestroyDescriptorPool)              \
  X(vkAllocateDescriptorSets)             \
  X(vkCreateAccelerationStructureKHR)     \
  X(vkDestroyAccelerationStructureKHR)    \
  X(vkCreateCommandPool)                  \
  X(vkDestroyCommandPool)                 \
  X(vkAllocateCommandBuffers)             \
  X(vkCreateSemaphore)                    \
  X(vkDestroySemaphore)                   \
  X(vkGetSemaphoreCounterValue)           \
  X(vkQueueSubmit)

}  // namespace

struct FailureInjector::State {
  PFN_vkGetInstanceProcAddr realGetInstanceProcAddr = nullptr;
  PFN_vkGetDeviceProcAddr realGetDeviceProcAddr = nullptr;
  struct Real {
#define RBTEST_DECLARE(name) PFN_##name name = nullptr;
    RBTEST_WRAPPED(RBTEST_DECLARE)
#undef RBTEST_DECLARE
  } real;

  struct Live {
    const char* type;
    const char* function;
    uint64_t call;
  };

  mutable std::mutex mutex;
  uint64_t failAt = 0;
  uint64_t count = 0;
  std::vector<std::string> log;
  std::vector<InjectedFailure> failures;
  std::unordered_map<std::string, uint64_t> perFunction;
  std::unordered_map<std::string, uint64_t> lostFrom;
  std::unordered_map<uint64_t, Live> live;
  std::vector<std::string> misuse;
  // Called on entry of every wrapper: VK_SUCCESS = forward the call, else return this result.
  VkResult enter(const char* function, bool counted, VkResult failure) {
    std::lock_guard<std::mutex> lock(mutex);
    const uint64_t n = ++perFunction[function];
    uint64_t index = 0;
    if (counted) {
      index = ++count;
      log.push_back(function);
    }
    if (auto it = lostFrom.find(function); it != lostFrom.end() && n >= it->second) {
      failures.push_back({index, function, VK_ERROR_DEVICE_LOST});
      return VK_ERROR_DEVICE_LOST;
    }
    if (counted && index == failAt) {
      failures.push_back({index, function, failure});
      return failure;
    }
    return VK_SUCCESS;
  }
  template <typename H>
  void created(H handle, const char* type, const char* function) {
    if (!handle) return;
    std::lock_guard<std::mutex> lock(mutex);
    live[key(handle)] = Live{type, function, count};
  }
  // True when the destroy may go on to the driver.
  template <typename H>
  bool destroyed(H handle, const char* function) {
    if (!handle) return true;  // destroying VK_NULL_HANDLE is valid and does nothing
    std::lock_guard<std::mutex> lock(mutex);
    if (live.erase(key(handle))) return true;
    misuse.push_back(std::string(function) + "(" + hex(key(handle)) + "): " +
                     (key(handle) == kPoison ? "the undefined handle that a failed create left behind"
                                             : "not created through the injector, or destroyed already"));
    return false;
  }
};

namespace {

FailureInjector::State* g = nullptr;

// Creates: counted, tracked; a failure leaves the poison in the output.
#define RBTEST_CREATE(name, Info, Handle, failure)                                                  \
  VKAPI_ATTR VkResult VKAPI_CALL wrap_##name(VkDevice device, const Info* info,                     \
                                             const VkAllocationCallbacks* allocator, Handle* out) { \
    if (VkResult r = g->enter(#name, true, failure); r != VK_SUCCESS) {                             \
      *out = poison<Handle>();                                                                      \
      return r;                                                                                     \
    }                                                                                               \
    VkResult r = g->real.name(device, info, allocator, out);                                        \
    if (r == VK_SUCCESS) g->created(*out, #Handle, #name);                                          \
    return r;                                                                                       \
  }
#define RBTEST_DESTROY(name, Handle)                                                                               \
  VKAPI_ATTR void VKAPI_CALL wrap_##name(VkDevice device, Handle handle, const VkAllocationCallbacks* allocator) { \
    if (g->destroyed(handle, #name)) g->real.name(device, handle, allocator);                                      \
  }

RBTEST_CREATE(vkAllocateMemory, VkMemoryAllocateInfo, VkDeviceMemory, VK_ERROR_OUT_OF_DEVICE_MEMORY)
RBTEST_DESTROY(vkFreeMemory, VkDeviceMemory)
RBTEST_CREATE(vkCreateBuffer, VkBufferCreateInfo, VkBuffer, VK_ERROR_OUT_OF_DEVICE_MEMORY)
RBTEST_DESTROY(vkDestroyBuffer, VkBuffer)
RBTEST_CREATE(vkCreateImage, VkImageCreateInfo, VkImage, VK_ERROR_OUT_OF_DEVICE_MEMORY)
RBTEST_DESTROY(vkDestroyImage, VkImage)
RBTEST_CREATE(vkCreateImageView, VkImageViewCreateInfo, VkImageView, VK_ERROR_OUT_OF_HOST_MEMORY)
RBTEST_DESTROY(vkDestroyImageView, VkImageView)
RBTEST_CREATE(vkCreateSampler, VkSamplerCreateInfo, VkSampler, VK_ERROR_OUT_OF_HOST_MEMORY)
RBTEST_DESTROY(vkDestroySampler, VkSampler)
RBTEST_CREATE(vkCreateQueryPool, VkQueryPoolCreateInfo, VkQueryPool, VK_ERROR_OUT_OF_HOST_MEMORY)
RBTEST_DESTROY(vkDestroyQueryPool, VkQueryPool)
RBTEST_CREATE(vkCreateShaderModule, VkShaderModuleCreateInfo, VkShaderModule, VK_ERROR_OUT_OF_HOST_MEMORY)
RBTEST_DESTROY(vkDestroyShaderModule, VkShaderModule)
RBTEST_CREATE(vkCreatePipelineLayout, VkPipelineLayoutCreateInfo, VkPipelineLayout, VK_ERROR_OUT_OF_HOST_MEMORY)
RBTEST_DESTROY(vkDestroyPipelineLayout, VkPipelineLayout)
RBTEST_DESTROY(vkDestroyPipeline, VkPipeline)
RBTEST_CREATE(vkCreateDescriptorSetLayout, VkDescriptorSetLayoutCreateInfo, VkDescriptorSetLayout,
              VK_ERROR_OUT_OF_HOST_MEMORY)
RBTEST_DESTROY(vkDestroyDescriptorSetLayout, VkDescriptorSetLayout)
RBTEST_CREATE(vkCreateDescriptorPool, VkDescriptorPoolCreateInfo, VkDescriptorPool, VK_ERROR_OUT_OF_HOST_MEMORY)
RBTEST_DESTROY(vkDestroyDescriptorPool, VkDescriptorPool)
RBTEST_CREATE(vkCreateAccelerationStructureKHR, VkAccelerationStructureCreateInfoKHR, VkAccelerationStructureKHR,
              VK_ERROR_OUT_OF_HOST_MEMORY)
RBTEST_DESTROY(vkDestroyAccelerationStructureKHR, VkAccelerationStructureKHR)
RBTEST_CREATE(vkCreateCommandPool, VkCommandPoolCreateInfo, VkCommandPool, VK_ERROR_OUT_OF_HOST_MEMORY)
RBTEST_DESTROY(vkDestroyCommandPool, VkCommandPool)
RBTEST_CREATE(vkCreateSemaphore, VkSemaphoreCreateInfo, VkSemaphore, VK_ERROR_OUT_OF_HOST_MEMORY)
RBTEST_DESTROY(vkDestroySemaphore, VkSemaphore)

#undef RBTEST_CREATE
#undef RBTEST_DESTROY

// Pipelines: a failure sets every output to VK_NULL_HANDLE (the spec's rule for pipeline creation).
VKAPI_ATTR VkResult VKAPI_CALL wrap_vkCreateComputePipelines(VkDevice device, VkPipelineCache cache, uint32_t count,
                                                             const VkComputePipelineCreateInfo* infos,
                                                             const VkAllocationCallbacks* allocator, VkPipeline* out) {
  if (VkResult r = g->enter("vkCreateComputePipelines", true, VK_ERROR_OUT_OF_HOST_MEMORY); r != VK_SUCCESS) {
    for (uint32_t i = 0; i < count; ++i) out[i] = VK_NULL_HANDLE;
    return r;
  }
  VkResult r = g->real.vkCreateComputePipelines(device, cache, count, infos, allocator, out);
  for (uint32_t i = 0; i < count; ++i) g->created(out[i], "VkPipeline", "vkCreateComputePipelines");
  return r;
}

VKAPI_ATTR VkResult VKAPI_CALL wrap_vkCreateRayTracingPipelinesKHR(VkDevice device, VkDeferredOperationKHR deferred,
                                                                   VkPipelineCache cache, uint32_t count,
                                                                   const VkRayTracingPipelineCreateInfoKHR* infos,
                                                                   const VkAllocationCallbacks* allocator,
                                                                   VkPipeline* out) {
  if (VkResult r = g->enter("vkCreateRayTracingPipelinesKHR", true, VK_ERROR_OUT_OF_HOST_MEMORY); r != VK_SUCCESS) {
    for (uint32_t i = 0; i < count; ++i) out[i] = VK_NULL_HANDLE;
    return r;
  }
  VkResult r = g->real.vkCreateRayTracingPipelinesKHR(device, deferred, cache, count, infos, allocator, out);
  for (uint32_t i = 0; i < count; ++i) g->created(out[i], "VkPipeline", "vkCreateRayTracingPipelinesKHR");
  return r;
}

VKAPI_ATTR VkResult VKAPI_CALL wrap_vkGetRayTracingShaderGroupHandlesKHR(VkDevice device, VkPipeline pipeline,
                                                                         uint32_t first, uint32_t count, size_t bytes,
                                                                         void* data) {
  if (VkResult r = g->enter("vkGetRayTracingShaderGroupHandlesKHR", true, VK_ERROR_OUT_OF_HOST_MEMORY);
      r != VK_SUCCESS) {
    std::memset(data, 0xBD, bytes);
    return r;
  }
  return g->real.vkGetRayTracingShaderGroupHandlesKHR(device, pipeline, first, count, bytes, data);
}

// Descriptor sets and command buffers are freed with their pools, so they are counted but not tracked; a failure
// sets every output to VK_NULL_HANDLE (the spec's rule for both).
VKAPI_ATTR VkResult VKAPI_CALL wrap_vkAllocateDescriptorSets(VkDevice device, const VkDescriptorSetAllocateInfo* info,
                                                             VkDescriptorSet* out) {
  if (VkResult r = g->enter("vkAllocateDescriptorSets", true, VK_ERROR_OUT_OF_POOL_MEMORY); r != VK_SUCCESS) {
    for (uint32_t i = 0; i < info->descriptorSetCount; ++i) out[i] = VK_NULL_HANDLE;
    return r;
  }
  return g->real.vkAllocateDescriptorSets(device, info, out);
}

VKAPI_ATTR VkResult VKAPI_CALL wrap_vkAllocateCommandBuffers(VkDevice device, const VkCommandBufferAllocateInfo* info,
                                                             VkCommandBuffer* out) {
  if (VkResult r = g->enter("vkAllocateCommandBuffers", true, VK_ERROR_OUT_OF_HOST_MEMORY); r != VK_SUCCESS) {
    for (uint32_t i = 0; i < info->commandBufferCount; ++i) out[i] = VK_NULL_HANDLE;
    return r;
  }
  return g->real.vkAllocateCommandBuffers(device, info, out);
}

VKAPI_ATTR VkResult VKAPI_CALL wrap_vkMapMemory(VkDevice device, VkDeviceMemory memory, VkDeviceSize offset,
                                                VkDeviceSize size, VkMemoryMapFlags flags, void** data) {
  if (VkResult r = g->enter("vkMapMemory", true, VK_ERROR_MEMORY_MAP_FAILED); r != VK_SUCCESS) {
    *data = reinterpret_cast<void*>(uintptr_t(kPoison));
    return r;
  }
  return g->real.vkMapMemory(device, memory, offset, size, flags, data);
}

VKAPI_ATTR VkResult VKAPI_CALL wrap_vkBindBufferMemory(VkDevice device, VkBuffer buffer, VkDeviceMemory memory,
                                                       VkDeviceSize offset) {
  if (VkResult r = g->enter("vkBindBufferMemory", true, VK_ERROR_OUT_OF_DEVICE_MEMORY); r != VK_SUCCESS) return r;
  return g->real.vkBindBufferMemory(device, buffer, memory, offset);
}

VKAPI_ATTR VkResult VKAPI_CALL wrap_vkBindImageMemory(VkDevice device, VkImage image, VkDeviceMemory memory,
                                                      VkDeviceSize offset) {
  if (VkResult r = g->enter("vkBindImageMemory", true, VK_ERROR_OUT_OF_DEVICE_MEMORY); r != VK_SUCCESS) return r;
  return g->real.vkBindImageMemory(device, image, memory, offset);
}

// What can report a lost device without allocating: never counted; on an injected loss the outputs are garbage.
VKAPI_ATTR VkResult VKAPI_CALL wrap_vkGetQueryPoolResults(VkDevice device, VkQueryPool pool, uint32_t first,
                                                          uint32_t count, size_t bytes, void* data, VkDeviceSize stride,
                                                          VkQueryResultFlags flags) {
  if (VkResult r = g->enter("vkGetQueryPoolResults", false, VK_SUCCESS); r != VK_SUCCESS) {
    std::memset(data, 0xFF, bytes);
    return r;
  }
  return g->real.vkGetQueryPoolResults(device, pool, first, count, bytes, data, stride, flags);
}

VKAPI_ATTR VkResult VKAPI_CALL wrap_vkGetSemaphoreCounterValue(VkDevice device, VkSemaphore semaphore,
                                                               uint64_t* value) {
  if (VkResult r = g->enter("vkGetSemaphoreCounterValue", false, VK_SUCCESS); r != VK_SUCCESS) {
    *value = UINT64_MAX;  // "everything is done": wrong, so a caller that uses it shows
    return r;
  }
  return g->real.vkGetSemaphoreCounterValue(device, semaphore, value);
}

VKAPI_ATTR VkResult VKAPI_CALL wrap_vkQueueSubmit(VkQueue queue, uint32_t count, const VkSubmitInfo* submits,
                                                  VkFence fence) {
  if (VkResult r = g->enter("vkQueueSubmit", false, VK_SUCCESS); r != VK_SUCCESS) return r;
  return g->real.vkQueueSubmit(queue, count, submits, fence);
}

// The wrapper of `name`, with its real function stored; nullptr when the injector does not wrap it.
PFN_vkVoidFunction wrapperOf(const char* name, PFN_vkVoidFunction real) {
  if (!real) return nullptr;
#define RBTEST_SELECT(fn)                                    \
  if (std::strcmp(name, #fn) == 0) {                         \
    g->real.fn = reinterpret_cast<PFN_##fn>(real);           \
    return reinterpret_cast<PFN_vkVoidFunction>(&wrap_##fn); \
  }
  RBTEST_WRAPPED(RBTEST_SELECT)
#undef RBTEST_SELECT
  return nullptr;
}

VKAPI_ATTR PFN_vkVoidFunction VKAPI_CALL injectingGetDeviceProcAddr(VkDevice device, const char* name) {
  PFN_vkVoidFunction real = g->realGetDeviceProcAddr(device, name);
  PFN_vkVoidFunction wrapper = wrapperOf(name, real);
  return wrapper ? wrapper : real;
}

VKAPI_ATTR PFN_vkVoidFunction VKAPI_CALL injectingGetInstanceProcAddr(VkInstance instance, const char* name) {
  PFN_vkVoidFunction real = g->realGetInstanceProcAddr(instance, name);
  if (std::strcmp(name, "vkGetDeviceProcAddr") == 0) {
    g->realGetDeviceProcAddr = reinterpret_cast<PFN_vkGetDeviceProcAddr>(real);
    return real ? reinterpret_cast<PFN_vkVoidFunction>(&injectingGetDeviceProcAddr) : nullptr;
  }
  PFN_vkVoidFunction wrapper = wrapperOf(name, real);
  return wrapper ? wrapper : real;
}

}  // namespace

FailureInjector::FailureInjector(PFN_vkGetInstanceProcAddr real) : state_(new State) {
  state_->realGetInstanceProcAddr = real;
  g = state_;
}

FailureInjector::~FailureInjector() {
  if (g == state_) g = nullptr;
  delete state_;
}

rb::ContextDesc FailureInjector::wrap(rb::ContextDesc desc) const {
  desc.getInstanceProcAddr = &injectingGetInstanceProcAddr;
  return desc;
}

void FailureInjector::reset() {
  std::lock_guard<std::mutex> lock(state_->mutex);
  state_->failAt = 0;
  state_->count = 0;
  state_->log.clear();
  state_->failures.clear();
  state_->perFunction.clear();
  state_->lostFrom.clear();
  state_->misuse.clear();
}

void FailureInjector::failCall(uint64_t k) {
  std::lock_guard<std::mutex> lock(state_->mutex);
  state_->failAt = k;
}

uint64_t FailureInjector::calls() const {
  std::lock_guard<std::mutex> lock(state_->mutex);
  return state_->count;
}

const std::vector<std::string>& FailureInjector::callLog() const { return state_->log; }
const std::vector<InjectedFailure>& FailureInjector::failures() const { return state_->failures; }

void FailureInjector::loseDevice(const std::string& function, uint64_t from) {
  std::lock_guard<std::mutex> lock(state_->mutex);
  state_->lostFrom[function] = from;
}

uint64_t FailureInjector::callsOf(const std::string& function) const {
  std::lock_guard<std::mutex> lock(state_->mutex);
  auto it = state_->perFunction.find(function);
  return it == state_->perFunction.end() ? 0 : it->second;
}

std::vector<std::string> FailureInjector::liveObjects() const {
  std::lock_guard<std::mutex> lock(state_->mutex);
  std::vector<std::string> out;
  for (const auto& [handle, l] : state_->live) {
    out.push_back(std::string(l.type) + " " + hex(handle) + " from " + l.function + " (allocation call " +
                  std::to_string(l.call) + ")");
  }
  return out;
}

const std::vector<std::string>& FailureInjector::misuse() const { return state_->misuse; }

}  // namespace rbtest
