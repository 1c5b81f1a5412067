#include <raybridge/headless_device.h>

#include <dlfcn.h>

#include <algorithm>
#include <cctype>
#include <cstdlib>
#include <cstring>
#include <mutex>
#include <string>
#include <vector>

#include "vulkan_errors.h"

namespace rb {

namespace {
// The instance's VkApplicationInfo::apiVersion, handed on in contextDesc().
constexpr uint32_t kHeadlessApiVersion = VK_API_VERSION_1_3;
}  // namespace

namespace {

std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return std::tolower(c); });
  return s;
}

bool envFlag(const char* name) {
  const char* v = std::getenv(name);
  return v && *v && std::strcmp(v, "0") != 0;
}

}  // namespace

struct HeadlessDevice::Impl {
  void* loader = nullptr;
  PFN_vkGetInstanceProcAddr gipa = nullptr;
  VkInstance instance = VK_NULL_HANDLE;
  VkPhysicalDevice physicalDevice = VK_NULL_HANDLE;
  VkDevice device = VK_NULL_HANDLE;
  VkQueue queue = VK_NULL_HANDLE;
  uint32_t queueFamily = 0;
  VkQueue asyncQueue = VK_NULL_HANDLE;
  uint32_t asyncFamily = UINT32_MAX;
  std::vector<uint32_t> bufferFamilies;  // both families when there is an async queue: concurrent buffers
  VkCommandPool pool = VK_NULL_HANDLE;
  VkDebugUtilsMessengerEXT messenger = VK_NULL_HANDLE;
  bool validation = false;
  uint32_t framesInFlight = 2;
  bool invocationReorder = false;
  std::string name;
  // The debug messenger calls onMessage on whichever thread made the Vulkan call (registerMesh runs on streaming
  // threads), possibly on several at once and while another thread reads the count: `errors` has its own mutex.
  mutable std::mutex errorsMutex;
  std::vector<std::string> errors;
  VkPhysicalDeviceMemoryProperties memoryProperties{};

  PFN_vkGetDeviceProcAddr gdpa = nullptr;
  template <typename T>
  T ip(const char* n) const {
    return reinterpret_cast<T>(gipa(instance, n));
  }
  template <typename T>
  T dp(const char* n) const {
    return reinterpret_cast<T>(gdpa(device, n));
  }

  static VKAPI_ATTR VkBool32 VKAPI_CALL onMessage(VkDebugUtilsMessageSeverityFlagBitsEXT severity,
                                                  VkDebugUtilsMessageTypeFlagsEXT,
                                                  const VkDebugUtilsMessengerCallbackDataEXT* data, void* user) {
    if (severity & VK_DEBUG_UTILS_MESSAGE_SEVERITY_ERROR_BIT_EXT) {
      auto* self = static_cast<Impl*>(user);
      std::lock_guard<std::mutex> lock(self->errorsMutex);
      self->errors.emplace_back(data->pMessage ? data->pMessage : "(no message)");
      if (self->errors.size() <= 20) std::fprintf(stderr, "[validation] %s\n", self->errors.back().c_str());
    }
    return VK_FALSE;
  }

  // The steps of HeadlessDevice::create, in order.
  Status openLoader();
  Status createInstance(const HeadlessDeviceDesc& desc);
  Status pickPhysicalDevice(const HeadlessDeviceDesc& desc);
  Status pickQueueFamilies(const HeadlessDeviceDesc& desc);
  Status createDevice(const HeadlessDeviceDesc& desc);
  Status createCommandPool();

  ~Impl() {
    if (device) {
      dp<PFN_vkDeviceWaitIdle>("vkDeviceWaitIdle")(device);
      if (pool) dp<PFN_vkDestroyCommandPool>("vkDestroyCommandPool")(device, pool, nullptr);
      dp<PFN_vkDestroyDevice>("vkDestroyDevice")(device, nullptr);
    }
    if (messenger) {
      ip<PFN_vkDestroyDebugUtilsMessengerEXT>("vkDestroyDebugUtilsMessengerEXT")(instance, messenger, nullptr);
    }
    if (instance) ip<PFN_vkDestroyInstance>("vkDestroyInstance")(instance, nullptr);
    if (loader) dlclose(loader);
  }
};

// The loader is opened at run time so neither the SDK nor its users link libvulkan at build time.
Status HeadlessDevice::Impl::openLoader() {
  loader = dlopen("libvulkan.so.1", RTLD_NOW | RTLD_LOCAL);
  if (!loader) loader = dlopen("libvulkan.so", RTLD_NOW | RTLD_LOCAL);
  if (!loader) {
    return Error{ErrorCode::NoSuitableDevice, VK_SUCCESS,
                 "the Vulkan loader libvulkan.so.1 was not found; install Debian's libvulkan1 (scripts/setup.sh)"};
  }
  gipa = reinterpret_cast<PFN_vkGetInstanceProcAddr>(dlsym(loader, "vkGetInstanceProcAddr"));
  return {};
}

// The instance, with the validation layer, synchronization validation and the error-counting messenger when
// validation is asked for (desc or RAYBRIDGE_VALIDATION) and installed.
Status HeadlessDevice::Impl::createInstance(const HeadlessDeviceDesc& desc) {
  auto createInstanceFn = ip<PFN_vkCreateInstance>("vkCreateInstance");
  auto enumerateLayers = ip<PFN_vkEnumerateInstanceLayerProperties>("vkEnumerateInstanceLayerProperties");

  bool wantValidation = desc.enableValidation || envFlag("RAYBRIDGE_VALIDATION");
  bool haveLayer = false;
  {
    uint32_t n = 0;
    enumerateLayers(&n, nullptr);
    std::vector<VkLayerProperties> layers(n);
    enumerateLayers(&n, layers.data());
    for (auto& l : layers) haveLayer |= std::strcmp(l.layerName, "VK_LAYER_KHRONOS_validation") == 0;
  }
  if (wantValidation && !haveLayer) {
    if (desc.requireValidation) {
      return Error{ErrorCode::MissingExtension, VK_SUCCESS,
                   "VK_LAYER_KHRONOS_validation is not installed; install Debian's vulkan-validationlayers or "
                   "point VK_LAYER_PATH at it"};
    }
    std::fprintf(stderr, "raybridge: validation requested but VK_LAYER_KHRONOS_validation is missing; continuing\n");
  }
  validation = wantValidation && haveLayer;

  VkApplicationInfo app{VK_STRUCTURE_TYPE_APPLICATION_INFO};
  app.pApplicationName = "raybridge-headless";
  app.apiVersion = kHeadlessApiVersion;
  std::vector<const char*> layers, extensions;
  if (validation) {
    layers.push_back("VK_LAYER_KHRONOS_validation");
    extensions.push_back(VK_EXT_DEBUG_UTILS_EXTENSION_NAME);
  }
  VkDebugUtilsMessengerCreateInfoEXT messengerInfo{VK_STRUCTURE_TYPE_DEBUG_UTILS_MESSENGER_CREATE_INFO_EXT};
  messengerInfo.messageSeverity = VK_DEBUG_UTILS_MESSAGE_SEVERITY_ERROR_BIT_EXT |
                                  VK_DEBUG_UTILS_MESSAGE_SEVERITY_WARNING_BIT_EXT;
  messengerInfo.messageType = VK_DEBUG_UTILS_MESSAGE_TYPE_GENERAL_BIT_EXT |
                              VK_DEBUG_UTILS_MESSAGE_TYPE_VALIDATION_BIT_EXT |
                              VK_DEBUG_UTILS_MESSAGE_TYPE_PERFORMANCE_BIT_EXT;
  messengerInfo.pfnUserCallback = &Impl::onMessage;
  messengerInfo.pUserData = this;
  VkValidationFeatureEnableEXT syncValidation = VK_VALIDATION_FEATURE_ENABLE_SYNCHRONIZATION_VALIDATION_EXT;
  VkValidationFeaturesEXT validationFeatures{VK_STRUCTURE_TYPE_VALIDATION_FEATURES_EXT, &messengerInfo};
  validationFeatures.enabledValidationFeatureCount = 1;
  validationFeatures.pEnabledValidationFeatures = &syncValidation;
  VkInstanceCreateInfo ici{VK_STRUCTURE_TYPE_INSTANCE_CREATE_INFO};
  ici.pNext = validation ? &validationFeatures : nullptr;
  ici.pApplicationInfo = &app;
  ici.enabledLayerCount = static_cast<uint32_t>(layers.size());
  ici.ppEnabledLayerNames = layers.data();
  ici.enabledExtensionCount = static_cast<uint32_t>(extensions.size());
  ici.ppEnabledExtensionNames = extensions.data();
  VkResult r = createInstanceFn(&ici, nullptr, &instance);
  if (r != VK_SUCCESS) return vulkanError(r, "vkCreateInstance");
  if (validation) {
    ip<PFN_vkCreateDebugUtilsMessengerEXT>("vkCreateDebugUtilsMessengerEXT")(instance, &messengerInfo, nullptr,
                                                                             &messenger);
  }
  return {};
}

// The best device (discrete, then integrated, then any) with every required extension whose name contains the
// filter (desc, else RAYBRIDGE_DEVICE).
Status HeadlessDevice::Impl::pickPhysicalDevice(const HeadlessDeviceDesc& desc) {
  auto enumerateDevices = ip<PFN_vkEnumeratePhysicalDevices>("vkEnumeratePhysicalDevices");
  auto getProps = ip<PFN_vkGetPhysicalDeviceProperties>("vkGetPhysicalDeviceProperties");
  auto enumerateExts = ip<PFN_vkEnumerateDeviceExtensionProperties>("vkEnumerateDeviceExtensionProperties");
  uint32_t count = 0;
  enumerateDevices(instance, &count, nullptr);
  std::vector<VkPhysicalDevice> devices(count);
  enumerateDevices(instance, &count, devices.data());

  std::string filter = desc.deviceNameFilter ? desc.deviceNameFilter : "";
  if (filter.empty() && std::getenv("RAYBRIDGE_DEVICE")) filter = std::getenv("RAYBRIDGE_DEVICE");
  filter = lower(filter);
  std::string seen;
  int bestScore = -1;
  for (VkPhysicalDevice pd : devices) {
    VkPhysicalDeviceProperties p;
    getProps(pd, &p);
    seen += std::string(seen.empty() ? "" : ", ") + p.deviceName;
    if (!filter.empty() && lower(p.deviceName).find(filter) == std::string::npos) continue;
    uint32_t n = 0;
    enumerateExts(pd, nullptr, &n, nullptr);
    std::vector<VkExtensionProperties> exts(n);
    enumerateExts(pd, nullptr, &n, exts.data());
    bool hasAll = true;
    for (const char* req : requiredDeviceExtensions()) {
      hasAll &= std::any_of(exts.begin(), exts.end(),
                            [&](const VkExtensionProperties& e) { return std::strcmp(e.extensionName, req) == 0; });
    }
    if (!hasAll) continue;
    int score = p.deviceType == VK_PHYSICAL_DEVICE_TYPE_DISCRETE_GPU     ? 3
                : p.deviceType == VK_PHYSICAL_DEVICE_TYPE_INTEGRATED_GPU ? 2
                                                                         : 1;
    if (score > bestScore) {
      bestScore = score;
      physicalDevice = pd;
      name = p.deviceName;
    }
  }
  if (!physicalDevice) {
    std::string why = filter.empty() ? "no device supports ray tracing pipelines"
                                     : "no device whose name contains '" + filter + "' supports ray tracing pipelines";
    return Error{ErrorCode::NoSuitableDevice, VK_SUCCESS,
                 why + " (devices: " + (seen.empty() ? "none" : seen) +
                     "). Install Mesa 25 lavapipe from bookworm-backports (scripts/setup.sh) or set RAYBRIDGE_DEVICE"};
  }
  return {};
}

// The first graphics+compute family; with desc.requestAsyncComputeQueue also a compute-only one.
Status HeadlessDevice::Impl::pickQueueFamilies(const HeadlessDeviceDesc& desc) {
  auto queueProps = ip<PFN_vkGetPhysicalDeviceQueueFamilyProperties>("vkGetPhysicalDeviceQueueFamilyProperties");
  uint32_t familyCount = 0;
  queueProps(physicalDevice, &familyCount, nullptr);
  std::vector<VkQueueFamilyProperties> families(familyCount);
  queueProps(physicalDevice, &familyCount, families.data());
  bool foundFamily = false;
  for (uint32_t i = 0; i < familyCount; ++i) {
    if ((families[i].queueFlags & (VK_QUEUE_GRAPHICS_BIT | VK_QUEUE_COMPUTE_BIT)) ==
        (VK_QUEUE_GRAPHICS_BIT | VK_QUEUE_COMPUTE_BIT)) {
      queueFamily = i;
      foundFamily = true;
      break;
    }
  }
  if (!foundFamily) {
    return Error{ErrorCode::NoSuitableDevice, VK_SUCCESS, "device '" + name + "' has no graphics+compute queue"};
  }
  if (desc.requestAsyncComputeQueue) {
    // A compute-only family; among several, one that can write timestamps.
    for (uint32_t i = 0; i < familyCount; ++i) {
      const VkQueueFlags f = families[i].queueFlags;
      if (!(f & VK_QUEUE_COMPUTE_BIT) || (f & VK_QUEUE_GRAPHICS_BIT) || families[i].queueCount == 0) continue;
      if (asyncFamily == UINT32_MAX ||
          (families[asyncFamily].timestampValidBits == 0 && families[i].timestampValidBits != 0)) {
        asyncFamily = i;
      }
    }
  }
  return {};
}

// The device with the required features and extensions (and invocation reorder where supported and not
// disabled), its queues and memory properties.
Status HeadlessDevice::Impl::createDevice(const HeadlessDeviceDesc& desc) {
  RequiredFeatures required;
  VkPhysicalDeviceVulkan13Features v13{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_3_FEATURES};
  v13.synchronization2 = VK_TRUE;
  v13.dynamicRendering = VK_TRUE;
  VkPhysicalDeviceFeatures2 features{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_FEATURES_2};
  features.pNext = required.link(&v13);
  features.features.shaderInt64 = VK_TRUE;
  float priority = 1.0f;
  VkDeviceQueueCreateInfo qci[2] = {{VK_STRUCTURE_TYPE_DEVICE_QUEUE_CREATE_INFO},
                                    {VK_STRUCTURE_TYPE_DEVICE_QUEUE_CREATE_INFO}};
  qci[0].queueFamilyIndex = queueFamily;
  qci[0].queueCount = 1;
  qci[0].pQueuePriorities = &priority;
  qci[1].queueFamilyIndex = asyncFamily;
  qci[1].queueCount = 1;
  qci[1].pQueuePriorities = &priority;
  std::vector<const char*> ext(requiredDeviceExtensions().begin(), requiredDeviceExtensions().end());
  // Optional features last in the chain: the feature struct of an extension is only chained with the extension.
  OptionalFeatures optional;
  invocationReorder = !desc.disableInvocationReorder && supportsInvocationReorder(instance, physicalDevice, gipa);
  if (invocationReorder) {
    ext.push_back(kInvocationReorderExtension);
    optional.invocationReorder.pNext = features.pNext;
    features.pNext = &optional.invocationReorder;
  }
  VkDeviceCreateInfo dci{VK_STRUCTURE_TYPE_DEVICE_CREATE_INFO, &features};
  dci.queueCreateInfoCount = asyncFamily == UINT32_MAX ? 1 : 2;
  dci.pQueueCreateInfos = qci;
  dci.enabledExtensionCount = static_cast<uint32_t>(ext.size());
  dci.ppEnabledExtensionNames = ext.data();
  VkResult r = ip<PFN_vkCreateDevice>("vkCreateDevice")(physicalDevice, &dci, nullptr, &device);
  if (r != VK_SUCCESS) return vulkanError(r, "vkCreateDevice on '" + name + "'");
  gdpa = ip<PFN_vkGetDeviceProcAddr>("vkGetDeviceProcAddr");
  dp<PFN_vkGetDeviceQueue>("vkGetDeviceQueue")(device, queueFamily, 0, &queue);
  if (asyncFamily != UINT32_MAX) {
    dp<PFN_vkGetDeviceQueue>("vkGetDeviceQueue")(device, asyncFamily, 0, &asyncQueue);
    bufferFamilies = {queueFamily, asyncFamily};
  }
  ip<PFN_vkGetPhysicalDeviceMemoryProperties>("vkGetPhysicalDeviceMemoryProperties")(physicalDevice, &memoryProperties);
  return {};
}

Status HeadlessDevice::Impl::createCommandPool() {
  VkCommandPoolCreateInfo pci{VK_STRUCTURE_TYPE_COMMAND_POOL_CREATE_INFO};
  pci.flags = VK_COMMAND_POOL_CREATE_RESET_COMMAND_BUFFER_BIT;
  pci.queueFamilyIndex = queueFamily;
  VkResult r = dp<PFN_vkCreateCommandPool>("vkCreateCommandPool")(device, &pci, nullptr, &pool);
  if (r != VK_SUCCESS) return vulkanError(r, "vkCreateCommandPool");
  return {};
}

Result<std::unique_ptr<HeadlessDevice>> HeadlessDevice::create(const HeadlessDeviceDesc& desc) {
  auto impl = std::make_unique<Impl>();
  impl->framesInFlight = desc.framesInFlight ? desc.framesInFlight : 2;
  if (Status st = impl->openLoader(); !st) return st.error();
  if (Status st = impl->createInstance(desc); !st) return st.error();
  if (Status st = impl->pickPhysicalDevice(desc); !st) return st.error();
  if (Status st = impl->pickQueueFamilies(desc); !st) return st.error();
  if (Status st = impl->createDevice(desc); !st) return st.error();
  if (Status st = impl->createCommandPool(); !st) return st.error();
  return std::unique_ptr<HeadlessDevice>(new HeadlessDevice(std::move(impl)));
}

HeadlessDevice::HeadlessDevice(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
HeadlessDevice::~HeadlessDevice() = default;

VkInstance HeadlessDevice::instance() const { return impl_->instance; }
VkPhysicalDevice HeadlessDevice::physicalDevice() const { return impl_->physicalDevice; }
VkDevice HeadlessDevice::device() const { return impl_->device; }
VkQueue HeadlessDevice::queue() const { return impl_->queue; }
uint32_t HeadlessDevice::queueFamily() const { return impl_->queueFamily; }
VkQueue HeadlessDevice::asyncComputeQueue() const { return impl_->asyncQueue; }
uint32_t HeadlessDevice::asyncComputeQueueFamily() const { return impl_->asyncFamily; }
PFN_vkGetInstanceProcAddr HeadlessDevice::getInstanceProcAddr() const { return impl_->gipa; }
PFN_vkVoidFunction HeadlessDevice::instanceProc(const char* name) const { return impl_->gipa(impl_->instance, name); }
PFN_vkVoidFunction HeadlessDevice::deviceProc(const char* name) const { return impl_->gdpa(impl_->device, name); }
std::string HeadlessDevice::deviceName() const { return impl_->name; }
uint32_t HeadlessDevice::validationErrorCount() const {
  std::lock_guard<std::mutex> lock(impl_->errorsMutex);
  return static_cast<uint32_t>(impl_->errors.size());
}
std::vector<std::string> HeadlessDevice::validationErrors() const {
  std::lock_guard<std::mutex> lock(impl_->errorsMutex);
  return impl_->errors;
}
bool HeadlessDevice::validationEnabled() const { return impl_->validation; }
bool HeadlessDevice::invocationReorderEnabled() const { return impl_->invocationReorder; }

ContextDesc HeadlessDevice::contextDesc() const {
  ContextDesc d;
  d.instance = impl_->instance;
  d.physicalDevice = impl_->physicalDevice;
  d.device = impl_->device;
  d.getInstanceProcAddr = impl_->gipa;
  d.framesInFlight = impl_->framesInFlight;
  d.mainQueueFamily = impl_->queueFamily;
  d.invocationReorderEnabled = impl_->invocationReorder;
  d.apiVersion = kHeadlessApiVersion;
  return d;
}

Result<VkCommandBuffer> HeadlessDevice::beginCommands() {
  VkCommandBufferAllocateInfo ai{VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO};
  ai.commandPool = impl_->pool;
  ai.level = VK_COMMAND_BUFFER_LEVEL_PRIMARY;
  ai.commandBufferCount = 1;
  VkCommandBuffer cmd = VK_NULL_HANDLE;
  VkResult r = impl_->dp<PFN_vkAllocateCommandBuffers>("vkAllocateCommandBuffers")(impl_->device, &ai, &cmd);
  if (r != VK_SUCCESS) return vulkanError(r, "vkAllocateCommandBuffers");
  VkCommandBufferBeginInfo bi{VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO};
  bi.flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT;
  r = impl_->dp<PFN_vkBeginCommandBuffer>("vkBeginCommandBuffer")(cmd, &bi);
  if (r != VK_SUCCESS) return vulkanError(r, "vkBeginCommandBuffer");
  return cmd;
}

Status HeadlessDevice::submitAndWait(VkCommandBuffer cmd) { return submitAndWait(cmd, {}, {}); }

Status HeadlessDevice::submitAndWait(VkCommandBuffer cmd, std::span<const VkSemaphoreSubmitInfo> waits,
                                     std::span<const VkSemaphoreSubmitInfo> signals) {
  Impl& d = *impl_;
  VkResult r = d.dp<PFN_vkEndCommandBuffer>("vkEndCommandBuffer")(cmd);
  auto freeCmd = [&] { d.dp<PFN_vkFreeCommandBuffers>("vkFreeCommandBuffers")(d.device, d.pool, 1, &cmd); };
  if (r != VK_SUCCESS) {
    freeCmd();
    return vulkanError(r, "vkEndCommandBuffer");
  }
  VkFenceCreateInfo fci{VK_STRUCTURE_TYPE_FENCE_CREATE_INFO};
  VkFence fence = VK_NULL_HANDLE;
  d.dp<PFN_vkCreateFence>("vkCreateFence")(d.device, &fci, nullptr, &fence);
  VkCommandBufferSubmitInfo ci{VK_STRUCTURE_TYPE_COMMAND_BUFFER_SUBMIT_INFO};
  ci.commandBuffer = cmd;
  VkSubmitInfo2 si{VK_STRUCTURE_TYPE_SUBMIT_INFO_2};
  si.waitSemaphoreInfoCount = static_cast<uint32_t>(waits.size());
  si.pWaitSemaphoreInfos = waits.data();
  si.commandBufferInfoCount = 1;
  si.pCommandBufferInfos = &ci;
  si.signalSemaphoreInfoCount = static_cast<uint32_t>(signals.size());
  si.pSignalSemaphoreInfos = signals.data();
  r = d.dp<PFN_vkQueueSubmit2>("vkQueueSubmit2")(d.queue, 1, &si, fence);
  if (r == VK_SUCCESS) r = d.dp<PFN_vkWaitForFences>("vkWaitForFences")(d.device, 1, &fence, VK_TRUE, UINT64_MAX);
  d.dp<PFN_vkDestroyFence>("vkDestroyFence")(d.device, fence, nullptr);
  freeCmd();
  if (r != VK_SUCCESS) return vulkanError(r, "vkQueueSubmit/vkWaitForFences");
  return {};
}

Result<VkSemaphore> HeadlessDevice::createTimelineSemaphore() {
  VkSemaphoreTypeCreateInfo type{VK_STRUCTURE_TYPE_SEMAPHORE_TYPE_CREATE_INFO};
  type.semaphoreType = VK_SEMAPHORE_TYPE_TIMELINE;
  VkSemaphoreCreateInfo si{VK_STRUCTURE_TYPE_SEMAPHORE_CREATE_INFO, &type};
  VkSemaphore semaphore = VK_NULL_HANDLE;
  VkResult r = impl_->dp<PFN_vkCreateSemaphore>("vkCreateSemaphore")(impl_->device, &si, nullptr, &semaphore);
  if (r != VK_SUCCESS) return vulkanError(r, "vkCreateSemaphore (timeline)");
  return semaphore;
}

void HeadlessDevice::destroySemaphore(VkSemaphore semaphore) {
  if (semaphore) impl_->dp<PFN_vkDestroySemaphore>("vkDestroySemaphore")(impl_->device, semaphore, nullptr);
}

Status HeadlessDevice::waitIdle() {
  VkResult r = impl_->dp<PFN_vkDeviceWaitIdle>("vkDeviceWaitIdle")(impl_->device);
  if (r != VK_SUCCESS) return vulkanError(r, "vkDeviceWaitIdle");
  return {};
}

Result<HeadlessBuffer> HeadlessDevice::createBuffer(VkDeviceSize size, VkBufferUsageFlags usage, bool hostVisible,
                                                    const void* data) {
  Impl& d = *impl_;
  HeadlessBuffer out;
  out.size = size;
  VkBufferCreateInfo bci{VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO};
  bci.size = size;
  bci.usage = usage | (hostVisible ? 0 : VK_BUFFER_USAGE_TRANSFER_DST_BIT | VK_BUFFER_USAGE_TRANSFER_SRC_BIT);
  if (!d.bufferFamilies.empty()) {
    // The async queue reads them too (dynamic BLAS builds): no ownership transfers needed.
    bci.sharingMode = VK_SHARING_MODE_CONCURRENT;
    bci.queueFamilyIndexCount = static_cast<uint32_t>(d.bufferFamilies.size());
    bci.pQueueFamilyIndices = d.bufferFamilies.data();
  }
  VkResult r = d.dp<PFN_vkCreateBuffer>("vkCreateBuffer")(d.device, &bci, nullptr, &out.buffer);
  if (r != VK_SUCCESS) return vulkanError(r, "vkCreateBuffer");
  VkMemoryRequirements req;
  d.dp<PFN_vkGetBufferMemoryRequirements>("vkGetBufferMemoryRequirements")(d.device, out.buffer, &req);
  VkMemoryPropertyFlags want = hostVisible ? VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT | VK_MEMORY_PROPERTY_HOST_COHERENT_BIT
                                           : VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT;
  uint32_t type = UINT32_MAX;
  for (uint32_t i = 0; i < d.memoryProperties.memoryTypeCount; ++i) {
    if ((req.memoryTypeBits & (1u << i)) && (d.memoryProperties.memoryTypes[i].propertyFlags & want) == want) {
      type = i;
      break;
    }
  }
  if (type == UINT32_MAX) {
    destroyBuffer(out);
    return Error{ErrorCode::VulkanError, VK_ERROR_OUT_OF_DEVICE_MEMORY, "no memory type for a headless buffer"};
  }
  VkMemoryAllocateFlagsInfo flags{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_FLAGS_INFO};
  flags.flags = VK_MEMORY_ALLOCATE_DEVICE_ADDRESS_BIT;
  VkMemoryAllocateInfo mai{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO};
  mai.pNext = (usage & VK_BUFFER_USAGE_SHADER_DEVICE_ADDRESS_BIT) ? &flags : nullptr;
  mai.allocationSize = req.size;
  mai.memoryTypeIndex = type;
  r = d.dp<PFN_vkAllocateMemory>("vkAllocateMemory")(d.device, &mai, nullptr, &out.memory);
  if (r != VK_SUCCESS) {
    destroyBuffer(out);
    return vulkanError(r, "vkAllocateMemory for a headless buffer of " + std::to_string(size) + " bytes");
  }
  d.dp<PFN_vkBindBufferMemory>("vkBindBufferMemory")(d.device, out.buffer, out.memory, 0);
  if (usage & VK_BUFFER_USAGE_SHADER_DEVICE_ADDRESS_BIT) {
    VkBufferDeviceAddressInfo ai{VK_STRUCTURE_TYPE_BUFFER_DEVICE_ADDRESS_INFO};
    ai.buffer = out.buffer;
    out.address = d.dp<PFN_vkGetBufferDeviceAddress>("vkGetBufferDeviceAddress")(d.device, &ai);
  }
  if (hostVisible) {
    d.dp<PFN_vkMapMemory>("vkMapMemory")(d.device, out.memory, 0, VK_WHOLE_SIZE, 0, &out.mapped);
    if (data) std::memcpy(out.mapped, data, size);
  } else if (data) {
    Result<HeadlessBuffer> staging = createBuffer(size, VK_BUFFER_USAGE_TRANSFER_SRC_BIT, true, data);
    if (!staging) {
      destroyBuffer(out);
      return staging.error();
    }
    Result<VkCommandBuffer> cmd = beginCommands();
    if (!cmd) {
      destroyBuffer(staging.value());
      destroyBuffer(out);
      return cmd.error();
    }
    VkBufferCopy region{0, 0, size};
    d.dp<PFN_vkCmdCopyBuffer>("vkCmdCopyBuffer")(cmd.value(), staging->buffer, out.buffer, 1, &region);
    Status s = submitAndWait(cmd.value());
    destroyBuffer(staging.value());
    if (!s) {
      destroyBuffer(out);
      return s.error();
    }
  }
  return out;
}

Status HeadlessDevice::readBuffer(const HeadlessBuffer& buffer, void* out, VkDeviceSize size) {
  if (buffer.mapped) {
    std::memcpy(out, buffer.mapped, size);
    return {};
  }
  Result<HeadlessBuffer> staging = createBuffer(size, VK_BUFFER_USAGE_TRANSFER_DST_BIT, true);
  if (!staging) return staging.error();
  Result<VkCommandBuffer> cmd = beginCommands();
  if (!cmd) {
    destroyBuffer(staging.value());
    return cmd.error();
  }
  VkBufferCopy region{0, 0, size};
  impl_->dp<PFN_vkCmdCopyBuffer>("vkCmdCopyBuffer")(cmd.value(), buffer.buffer, staging->buffer, 1, &region);
  Status s = submitAndWait(cmd.value());
  if (s) std::memcpy(out, staging->mapped, size);
  destroyBuffer(staging.value());
  return s;
}

void HeadlessDevice::destroyBuffer(HeadlessBuffer& buffer) {
  if (buffer.buffer) impl_->dp<PFN_vkDestroyBuffer>("vkDestroyBuffer")(impl_->device, buffer.buffer, nullptr);
  if (buffer.memory) impl_->dp<PFN_vkFreeMemory>("vkFreeMemory")(impl_->device, buffer.memory, nullptr);
  buffer = HeadlessBuffer{};
}

}  // namespace rb
