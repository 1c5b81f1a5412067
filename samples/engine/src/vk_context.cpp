// Vulkan bootstrap. The device is created so that an add-on can share it: caller extensions and feature
// structs are merged in, and everything is exposed through Engine's accessors.
#include "vk_context.h"

#include <algorithm>
#include <cstddef>
#include <cstdio>
#include <cstdlib>
#include <cstring>

#include "vk_check.h"

namespace sample_engine::detail {

std::string vkResultName(VkResult r) {
  switch (r) {
#define SE_CASE(x) \
  case x: return #x;
    SE_CASE(VK_SUCCESS)
    SE_CASE(VK_NOT_READY)
    SE_CASE(VK_TIMEOUT)
    SE_CASE(VK_INCOMPLETE)
    SE_CASE(VK_SUBOPTIMAL_KHR)
    SE_CASE(VK_ERROR_OUT_OF_HOST_MEMORY)
    SE_CASE(VK_ERROR_OUT_OF_DEVICE_MEMORY)
    SE_CASE(VK_ERROR_INITIALIZATION_FAILED)
    SE_CASE(VK_ERROR_DEVICE_LOST)
    SE_CASE(VK_ERROR_MEMORY_MAP_FAILED)
    SE_CASE(VK_ERROR_LAYER_NOT_PRESENT)
    SE_CASE(VK_ERROR_EXTENSION_NOT_PRESENT)
    SE_CASE(VK_ERROR_FEATURE_NOT_PRESENT)
    SE_CASE(VK_ERROR_INCOMPATIBLE_DRIVER)
    SE_CASE(VK_ERROR_TOO_MANY_OBJECTS)
    SE_CASE(VK_ERROR_FORMAT_NOT_SUPPORTED)
    SE_CASE(VK_ERROR_SURFACE_LOST_KHR)
    SE_CASE(VK_ERROR_OUT_OF_DATE_KHR)
    SE_CASE(VK_ERROR_NATIVE_WINDOW_IN_USE_KHR)
#undef SE_CASE
    default: return "VkResult(" + std::to_string(int(r)) + ")";
  }
}

namespace {

VKAPI_ATTR VkBool32 VKAPI_CALL debugCallback(VkDebugUtilsMessageSeverityFlagBitsEXT severity,
                                             VkDebugUtilsMessageTypeFlagsEXT,
                                             const VkDebugUtilsMessengerCallbackDataEXT* data, void* user) {
  auto* counters = static_cast<ValidationCounters*>(user);
  if (severity & VK_DEBUG_UTILS_MESSAGE_SEVERITY_ERROR_BIT_EXT) {
    counters->errors++;
    std::fprintf(stderr, "[sample_engine validation error] %s\n", data->pMessage);
  } else if (severity & VK_DEBUG_UTILS_MESSAGE_SEVERITY_WARNING_BIT_EXT) {
    counters->warnings++;
    std::fprintf(stderr, "[sample_engine validation warning] %s\n", data->pMessage);
  }
  return VK_FALSE;
}

bool hasLayer(const char* name) {
  uint32_t n = 0;
  vkEnumerateInstanceLayerProperties(&n, nullptr);
  std::vector<VkLayerProperties> layers(n);
  vkEnumerateInstanceLayerProperties(&n, layers.data());
  return std::any_of(layers.begin(), layers.end(), [&](const auto& l) { return std::strcmp(l.layerName, name) == 0; });
}

std::vector<std::string> deviceExtensionNames(VkPhysicalDevice pd) {
  uint32_t n = 0;
  vkEnumerateDeviceExtensionProperties(pd, nullptr, &n, nullptr);
  std::vector<VkExtensionProperties> props(n);
  vkEnumerateDeviceExtensionProperties(pd, nullptr, &n, props.data());
  std::vector<std::string> names;
  for (const auto& p : props) names.emplace_back(p.extensionName);
  return names;
}

// ORs every VkBool32 of `extra` into `dst`. Core feature structs are plain VkBool32 sequences after their
// sType/pNext header, starting at `firstOffset`.
template <typename T>
void mergeBools(T& dst, const T& extra, size_t firstOffset) {
  auto* d = reinterpret_cast<VkBool32*>(reinterpret_cast<char*>(&dst) + firstOffset);
  auto* s = reinterpret_cast<const VkBool32*>(reinterpret_cast<const char*>(&extra) + firstOffset);
  for (size_t i = 0; i < (sizeof(T) - firstOffset) / sizeof(VkBool32); ++i) d[i] = d[i] || s[i];
}

struct Candidate {
  VkPhysicalDevice device;
  VkPhysicalDeviceProperties props;
  uint32_t family;
};

}  // namespace

std::string VulkanContext::create(const EngineConfig& config) {
  queueSubmit2 = config.queueSubmit2 ? config.queueSubmit2 : &vkQueueSubmit2;
  waitForFences = config.waitForFences ? config.waitForFences : &vkWaitForFences;
  // --- Instance ---
  std::vector<const char*> layers;
  std::vector<std::string> instanceExts = config.instanceExtensions;
  if (config.enableValidation) {
    if (!hasLayer("VK_LAYER_KHRONOS_validation"))
      return "validation requested but VK_LAYER_KHRONOS_validation is not installed";
    layers.push_back("VK_LAYER_KHRONOS_validation");
    instanceExts.emplace_back(VK_EXT_DEBUG_UTILS_EXTENSION_NAME);
  }
  std::sort(instanceExts.begin(), instanceExts.end());
  instanceExts.erase(std::unique(instanceExts.begin(), instanceExts.end()), instanceExts.end());
  std::vector<const char*> instanceExtPtrs;
  for (const auto& e : instanceExts) instanceExtPtrs.push_back(e.c_str());

  VkApplicationInfo app{VK_STRUCTURE_TYPE_APPLICATION_INFO};
  app.pApplicationName = config.applicationName.c_str();
  app.pEngineName = "raybridge-sample-engine";
  app.apiVersion = VK_API_VERSION_1_3;
  VkDebugUtilsMessengerCreateInfoEXT messengerInfo{VK_STRUCTURE_TYPE_DEBUG_UTILS_MESSENGER_CREATE_INFO_EXT};
  messengerInfo.messageSeverity = VK_DEBUG_UTILS_MESSAGE_SEVERITY_WARNING_BIT_EXT |
                                  VK_DEBUG_UTILS_MESSAGE_SEVERITY_ERROR_BIT_EXT;
  messengerInfo.messageType = VK_DEBUG_UTILS_MESSAGE_TYPE_GENERAL_BIT_EXT |
                              VK_DEBUG_UTILS_MESSAGE_TYPE_VALIDATION_BIT_EXT |
                              VK_DEBUG_UTILS_MESSAGE_TYPE_PERFORMANCE_BIT_EXT;
  messengerInfo.pfnUserCallback = debugCallback;
  messengerInfo.pUserData = counters.get();
  VkInstanceCreateInfo ici{VK_STRUCTURE_TYPE_INSTANCE_CREATE_INFO};
  ici.pNext = config.enableValidation ? &messengerInfo : nullptr;  // also covers create/destroy
  ici.pApplicationInfo = &app;
  ici.enabledLayerCount = uint32_t(layers.size());
  ici.ppEnabledLayerNames = layers.data();
  ici.enabledExtensionCount = uint32_t(instanceExtPtrs.size());
  ici.ppEnabledExtensionNames = instanceExtPtrs.data();
  SE_VK_TRY(vkCreateInstance(&ici, nullptr, &instance));
  if (config.enableValidation) {
    auto createMessenger = reinterpret_cast<PFN_vkCreateDebugUtilsMessengerEXT>(
        vkGetInstanceProcAddr(instance, "vkCreateDebugUtilsMessengerEXT"));
    if (!createMessenger) return "vkCreateDebugUtilsMessengerEXT not available";
    SE_VK_TRY(createMessenger(instance, &messengerInfo, nullptr, &messenger));
  }

  // --- Physical device ---
  std::vector<std::string> requiredExts = config.deviceExtensions;
  if (config.enableSwapchain) requiredExts.emplace_back(VK_KHR_SWAPCHAIN_EXTENSION_NAME);
  std::sort(requiredExts.begin(), requiredExts.end());
  requiredExts.erase(std::unique(requiredExts.begin(), requiredExts.end()), requiredExts.end());

  std::string filter = config.deviceNameFilter;
  if (filter.empty())
    if (const char* env = std::getenv("SAMPLE_ENGINE_DEVICE")) filter = env;

  uint32_t count = 0;
  vkEnumeratePhysicalDevices(instance, &count, nullptr);
  std::vector<VkPhysicalDevice> devices(count);
  vkEnumeratePhysicalDevices(instance, &count, devices.data());
  std::vector<Candidate> candidates;
  std::string rejected;
  for (VkPhysicalDevice pd : devices) {
    Candidate c{pd, {}, UINT32_MAX};
    vkGetPhysicalDeviceProperties(pd, &c.props);
    const std::string name = c.props.deviceName;
    auto reject = [&](const std::string& why) { rejected += "\n  " + name + ": " + why; };
    if (!filter.empty() && name.find(filter) == std::string::npos) {
      reject("name does not contain '" + filter + "'");
      continue;
    }
    if (c.props.apiVersion < VK_API_VERSION_1_3) {
      reject("Vulkan 1.3 not supported");
      continue;
    }
    uint32_t nf = 0;
    vkGetPhysicalDeviceQueueFamilyProperties(pd, &nf, nullptr);
    std::vector<VkQueueFamilyProperties> families(nf);
    vkGetPhysicalDeviceQueueFamilyProperties(pd, &nf, families.data());
    for (uint32_t f = 0; f < nf && c.family == UINT32_MAX; ++f)
      if ((families[f].queueFlags & VK_QUEUE_GRAPHICS_BIT) && (families[f].queueFlags & VK_QUEUE_COMPUTE_BIT))
        c.family = f;
    if (c.family == UINT32_MAX) {
      reject("no graphics+compute queue family");
      continue;
    }
    std::vector<std::string> have = deviceExtensionNames(pd);
    std::string missing;
    for (const auto& e : requiredExts)
      if (std::find(have.begin(), have.end(), e) == have.end()) missing += " " + e;
    if (!missing.empty()) {
      reject("missing device extensions:" + missing);
      continue;
    }
    VkPhysicalDeviceVulkan12Features f12{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_2_FEATURES};
    VkPhysicalDeviceVulkan13Features f13{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_3_FEATURES};
    f12.pNext = &f13;
    VkPhysicalDeviceFeatures2 f2{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_FEATURES_2, &f12, {}};
    vkGetPhysicalDeviceFeatures2(pd, &f2);
    if (!f13.dynamicRendering || !f13.synchronization2 || !f12.separateDepthStencilLayouts || !f12.timelineSemaphore ||
        !f2.features.shaderStorageImageExtendedFormats) {
      reject("dynamicRendering / synchronization2 / separateDepthStencilLayouts / timelineSemaphore / "
             "shaderStorageImageExtendedFormats unsupported");
      continue;
    }
    candidates.push_back(c);
  }
  if (candidates.empty())
    return "no suitable Vulkan 1.3 device found:" + (rejected.empty() ? std::string(" none enumerated") : rejected);
  auto chosen = std::find_if(candidates.begin(), candidates.end(), [](const Candidate& c) {
    return c.props.deviceType == VK_PHYSICAL_DEVICE_TYPE_DISCRETE_GPU;
  });
  if (chosen == candidates.end()) chosen = candidates.begin();
  physicalDevice = chosen->device;
  properties = chosen->props;
  queueFamily = chosen->family;
  info.name = properties.deviceName;
  info.apiVersion = properties.apiVersion;
  info.type = properties.deviceType;

  // --- Features: the engine's needs, OR-ed with the caller's ---
  for (const auto* s = static_cast<const VkBaseInStructure*>(config.deviceFeaturesPNext); s; s = s->pNext) {
    if (s->sType == VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_FEATURES_2 ||
        s->sType == VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_1_FEATURES ||
        s->sType == VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_2_FEATURES ||
        s->sType == VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_3_FEATURES)
      return "EngineConfig::deviceFeaturesPNext must not contain core feature structs; use "
             "EngineConfig::extraFeatures10/11/12/13 instead";
  }
  VkPhysicalDeviceVulkan12Features supported12{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_2_FEATURES};
  VkPhysicalDeviceFeatures2 supported{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_FEATURES_2, &supported12, {}};
  vkGetPhysicalDeviceFeatures2(physicalDevice, &supported);

  VkPhysicalDeviceVulkan11Features f11{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_1_FEATURES};
  VkPhysicalDeviceVulkan12Features f12{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_2_FEATURES};
  VkPhysicalDeviceVulkan13Features f13{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_3_FEATURES};
  VkPhysicalDeviceFeatures2 f2{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_FEATURES_2};
  f13.dynamicRendering = VK_TRUE;
  f13.synchronization2 = VK_TRUE;
  f12.separateDepthStencilLayouts = VK_TRUE;  // lets the pre-pass depth sit in DEPTH_READ_ONLY_OPTIMAL
  f12.timelineSemaphore = VK_TRUE;            // the deformation submission signals a timeline semaphore per frame
  f2.features.shaderStorageImageExtendedFormats = VK_TRUE;  // the SSAO compute passes write R16F storage images
  // Required by Vulkan 1.3, so always on: the deformation pass reads and writes vertex buffers through
  // device addresses, and mesh.vert reads last frame's model matrices (motion vectors) through one. Scene buffers
  // expose addresses only with enableRayTracingInputs (info.bufferDeviceAddress).
  f12.bufferDeviceAddress = supported12.bufferDeviceAddress;
  mergeBools(f2.features, config.extraFeatures10, 0);
  mergeBools(f11, config.extraFeatures11, offsetof(VkPhysicalDeviceVulkan11Features, storageBuffer16BitAccess));
  mergeBools(f12, config.extraFeatures12, offsetof(VkPhysicalDeviceVulkan12Features, samplerMirrorClampToEdge));
  mergeBools(f13, config.extraFeatures13, offsetof(VkPhysicalDeviceVulkan13Features, robustImageAccess));
  f2.pNext = &f11;
  f11.pNext = &f12;
  f12.pNext = &f13;
  f13.pNext = const_cast<void*>(config.deviceFeaturesPNext);
  bufferDeviceAddressFeature = f12.bufferDeviceAddress;
  info.bufferDeviceAddress = config.enableRayTracingInputs && f12.bufferDeviceAddress;

  // Optional extensions the chosen device has, with their feature structs as supported (an unsupported feature
  // cannot be enabled, and a struct is only valid with its extension).
  std::vector<std::string> optionalExts;
  {
    std::vector<std::string> have = deviceExtensionNames(physicalDevice);
    for (const auto& o : config.optionalDeviceExtensions) {
      if (std::find(have.begin(), have.end(), o.name) == have.end()) continue;
      optionalExts.push_back(o.name);
      if (!o.features) continue;
      auto* s = static_cast<VkBaseOutStructure*>(o.features);
      s->pNext = nullptr;
      VkPhysicalDeviceFeatures2 query{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_FEATURES_2, s, {}};
      vkGetPhysicalDeviceFeatures2(physicalDevice, &query);
      s->pNext = static_cast<VkBaseOutStructure*>(f2.pNext);
      f2.pNext = s;
    }
  }

  // --- Device ---
  deviceExtensions = requiredExts;
  for (const auto& e : optionalExts)
    if (std::find(deviceExtensions.begin(), deviceExtensions.end(), e) == deviceExtensions.end())
      deviceExtensions.push_back(e);
  swapchainEnabled = config.enableSwapchain;
  accelerationStructureEnabled = std::find(deviceExtensions.begin(), deviceExtensions.end(),
                                           VK_KHR_ACCELERATION_STRUCTURE_EXTENSION_NAME) != deviceExtensions.end();
  std::vector<const char*> extPtrs;
  for (const auto& e : deviceExtensions) extPtrs.push_back(e.c_str());
  uint32_t nf = 0;
  vkGetPhysicalDeviceQueueFamilyProperties(physicalDevice, &nf, nullptr);
  std::vector<VkQueueFamilyProperties> families(nf);
  vkGetPhysicalDeviceQueueFamilyProperties(physicalDevice, &nf, families.data());
  if (config.requestAsyncComputeQueue)
    for (uint32_t f = 0; f < nf && asyncComputeFamily == UINT32_MAX; ++f)
      if ((families[f].queueFlags & VK_QUEUE_COMPUTE_BIT) && !(families[f].queueFlags & VK_QUEUE_GRAPHICS_BIT) &&
          families[f].queueCount > 0)
        asyncComputeFamily = f;
  const float priority = 1.0f;
  VkDeviceQueueCreateInfo qci[2] = {{VK_STRUCTURE_TYPE_DEVICE_QUEUE_CREATE_INFO},
                                    {VK_STRUCTURE_TYPE_DEVICE_QUEUE_CREATE_INFO}};
  qci[0].queueFamilyIndex = queueFamily;
  qci[0].queueCount = 1;
  qci[0].pQueuePriorities = &priority;
  qci[1].queueFamilyIndex = asyncComputeFamily;
  qci[1].queueCount = 1;
  qci[1].pQueuePriorities = &priority;
  VkDeviceCreateInfo dci{VK_STRUCTURE_TYPE_DEVICE_CREATE_INFO};
  dci.pNext = &f2;
  dci.queueCreateInfoCount = asyncComputeFamily != UINT32_MAX ? 2 : 1;
  dci.pQueueCreateInfos = qci;
  dci.enabledExtensionCount = uint32_t(extPtrs.size());
  dci.ppEnabledExtensionNames = extPtrs.data();
  SE_VK_TRY(vkCreateDevice(physicalDevice, &dci, nullptr, &device));
  vkGetDeviceQueue(device, queueFamily, 0, &queue);
  if (asyncComputeFamily != UINT32_MAX) vkGetDeviceQueue(device, asyncComputeFamily, 0, &asyncComputeQueue);
  timestampsSupported = families[queueFamily].timestampValidBits > 0 && properties.limits.timestampPeriod > 0;
  timestampPeriodNs = properties.limits.timestampPeriod;
  return {};
}

void VulkanContext::destroy() {
  if (device) vkDestroyDevice(device, nullptr);
  device = VK_NULL_HANDLE;
  if (messenger) {
    auto destroyMessenger = reinterpret_cast<PFN_vkDestroyDebugUtilsMessengerEXT>(
        vkGetInstanceProcAddr(instance, "vkDestroyDebugUtilsMessengerEXT"));
    if (destroyMessenger) destroyMessenger(instance, messenger, nullptr);
    messenger = VK_NULL_HANDLE;
  }
  if (instance) vkDestroyInstance(instance, nullptr);
  instance = VK_NULL_HANDLE;
}

}  // namespace sample_engine::detail
