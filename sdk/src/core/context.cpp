#include <raybridge/context.h>

#include <algorithm>
#include <cstring>
#include <string>
#include <vector>

#include "context_impl.h"

namespace rb {

namespace {

constexpr const char* kRequiredExtensions[] = {
    VK_KHR_ACCELERATION_STRUCTURE_EXTENSION_NAME,
    VK_KHR_RAY_TRACING_PIPELINE_EXTENSION_NAME,
    VK_KHR_DEFERRED_HOST_OPERATIONS_EXTENSION_NAME,
    VK_KHR_PUSH_DESCRIPTOR_EXTENSION_NAME,
};

std::vector<VkExtensionProperties> deviceExtensions(const DeviceFunctions& vk, VkPhysicalDevice physicalDevice) {
  uint32_t count = 0;
  vk.vkEnumerateDeviceExtensionProperties(physicalDevice, nullptr, &count, nullptr);
  std::vector<VkExtensionProperties> available(count);
  vk.vkEnumerateDeviceExtensionProperties(physicalDevice, nullptr, &count, available.data());
  return available;
}

bool hasExtension(const std::vector<VkExtensionProperties>& available, const char* name) {
  return std::any_of(available.begin(), available.end(),
                     [&](const VkExtensionProperties& e) { return std::strcmp(e.extensionName, name) == 0; });
}

Status checkExtensions(const std::vector<VkExtensionProperties>& available, const std::string& deviceName) {
  std::string missing;
  for (const char* name : kRequiredExtensions) {
    if (!hasExtension(available, name)) missing += std::string(missing.empty() ? "" : ", ") + name;
  }
  if (!missing.empty()) {
    return Error{ErrorCode::MissingExtension, VK_SUCCESS,
                 "device '" + deviceName + "' does not support the extensions Raybridge needs: " + missing +
                     ". Use a device with hardware or software ray tracing pipelines (e.g. Mesa 25 lavapipe)."};
  }
  return {};
}

std::string versionString(uint32_t v) {
  return std::to_string(VK_API_VERSION_MAJOR(v)) + "." + std::to_string(VK_API_VERSION_MINOR(v));
}

// `apiVersion`: ContextDesc::apiVersion (0 = not stated).
Status checkFeatures(const DeviceFunctions& vk, VkPhysicalDevice physicalDevice, const std::string& deviceName,
                     uint32_t apiVersion) {
  VkPhysicalDeviceRayTracingPipelineFeaturesKHR rt{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_RAY_TRACING_PIPELINE_FEATURES_KHR};
  VkPhysicalDeviceAccelerationStructureFeaturesKHR as{
      VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_ACCELERATION_STRUCTURE_FEATURES_KHR, &rt};
  VkPhysicalDeviceVulkan12Features v12{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_2_FEATURES, &as};
  VkPhysicalDeviceFeatures2 f2{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_FEATURES_2, &v12};
  vk.vkGetPhysicalDeviceFeatures2(physicalDevice, &f2);
  std::string missing;
  auto need = [&](VkBool32 v, const char* name) {
    if (!v) missing += std::string(missing.empty() ? "" : ", ") + name;
  };
  need(v12.bufferDeviceAddress, "bufferDeviceAddress");
  need(v12.descriptorIndexing, "descriptorIndexing");
  need(v12.runtimeDescriptorArray, "runtimeDescriptorArray");
  need(v12.shaderSampledImageArrayNonUniformIndexing, "shaderSampledImageArrayNonUniformIndexing");
  need(v12.scalarBlockLayout, "scalarBlockLayout");
  need(v12.descriptorBindingPartiallyBound, "descriptorBindingPartiallyBound");
  need(v12.descriptorBindingVariableDescriptorCount, "descriptorBindingVariableDescriptorCount");
  need(v12.timelineSemaphore, "timelineSemaphore");
  need(as.accelerationStructure, "accelerationStructure");
  need(rt.rayTracingPipeline, "rayTracingPipeline");
  // The shadow pass traces the tiles its classifier lists with vkCmdTraceRaysIndirectKHR.
  need(rt.rayTracingPipelineTraceRaysIndirect, "rayTracingPipelineTraceRaysIndirect");
  // The many-light tile culling counts the lights of a tile with subgroup ballots (every ray tracing driver seen
  // has them: NVIDIA, AMD, Intel, lavapipe).
  VkPhysicalDeviceSubgroupProperties subgroup{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_SUBGROUP_PROPERTIES};
  VkPhysicalDeviceProperties2 p2{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_PROPERTIES_2, &subgroup};
  vk.vkGetPhysicalDeviceProperties2(physicalDevice, &p2);
  need((subgroup.supportedStages & VK_SHADER_STAGE_COMPUTE_BIT) &&
           (subgroup.supportedOperations & VK_SUBGROUP_FEATURE_BALLOT_BIT),
       "subgroup ballot operations in compute shaders");
  // An instance created with VkApplicationInfo::apiVersion 1.0 or 1.1 gets no Vulkan 1.2 features from a 1.2
  // device: every one of them reads false. Say so, rather than blame the device.
  const bool no12Feature = !v12.bufferDeviceAddress && !v12.descriptorIndexing && !v12.scalarBlockLayout &&
                           !v12.timelineSemaphore && !v12.runtimeDescriptorArray;
  if (apiVersion == 0 && no12Feature) {
    return Error{ErrorCode::UnsupportedApiVersion, VK_SUCCESS,
                 "device '" + deviceName + "' reports none of the Vulkan 1.2 features (" + missing +
                     "), which is what an instance created with VkApplicationInfo::apiVersion below 1.2 sees: "
                     "create the instance with apiVersion = VK_API_VERSION_1_2 or newer (and pass it in "
                     "ContextDesc::apiVersion)"};
  }
  if (!missing.empty()) {
    return Error{ErrorCode::MissingFeature, VK_SUCCESS,
                 "device '" + deviceName + "' does not support the features Raybridge needs: " + missing};
  }
  return {};
}

bool hasInvocationReorderFeature(const DeviceFunctions& vk, VkPhysicalDevice physicalDevice) {
  VkPhysicalDeviceRayTracingInvocationReorderFeaturesNV ser{
      VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_RAY_TRACING_INVOCATION_REORDER_FEATURES_NV};
  VkPhysicalDeviceFeatures2 f2{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_FEATURES_2, &ser};
  vk.vkGetPhysicalDeviceFeatures2(physicalDevice, &f2);
  return ser.rayTracingInvocationReorder == VK_TRUE;
}

// ContextDesc::invocationReorderEnabled against what the physical device supports: a device that lacks it cannot
// have enabled it, and a pipeline using it there would fail to build (or crash the driver) much later.
Status checkInvocationReorder(const DeviceFunctions& vk, VkPhysicalDevice physicalDevice,
                              const std::vector<VkExtensionProperties>& available, const std::string& deviceName) {
  if (!hasExtension(available, kInvocationReorderExtension)) {
    return Error{ErrorCode::MissingExtension, VK_SUCCESS,
                 "ContextDesc::invocationReorderEnabled is true but device '" + deviceName + "' does not support " +
                     kInvocationReorderExtension + "; set it only where rb::supportsInvocationReorder() is true"};
  }
  if (!hasInvocationReorderFeature(vk, physicalDevice)) {
    return Error{ErrorCode::MissingFeature, VK_SUCCESS,
                 "ContextDesc::invocationReorderEnabled is true but device '" + deviceName +
                     "' does not support the feature rayTracingInvocationReorder"};
  }
  return {};
}

}  // namespace

bool supportsInvocationReorder(VkInstance instance, VkPhysicalDevice physicalDevice,
                               PFN_vkGetInstanceProcAddr getInstanceProcAddr) {
  if (!instance || !physicalDevice || !getInstanceProcAddr) return false;
  DeviceFunctions vk;
  vk.vkGetPhysicalDeviceFeatures2 = reinterpret_cast<PFN_vkGetPhysicalDeviceFeatures2>(
      getInstanceProcAddr(instance, "vkGetPhysicalDeviceFeatures2"));
  vk.vkEnumerateDeviceExtensionProperties = reinterpret_cast<PFN_vkEnumerateDeviceExtensionProperties>(
      getInstanceProcAddr(instance, "vkEnumerateDeviceExtensionProperties"));
  if (!vk.vkGetPhysicalDeviceFeatures2 || !vk.vkEnumerateDeviceExtensionProperties) return false;
  // The feature struct is only defined for a device with the extension: ask for it after the extension.
  return hasExtension(deviceExtensions(vk, physicalDevice), kInvocationReorderExtension) &&
         hasInvocationReorderFeature(vk, physicalDevice);
}

OptionalFeatures::OptionalFeatures() {
  invocationReorder.sType = VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_RAY_TRACING_INVOCATION_REORDER_FEATURES_NV;
  invocationReorder.pNext = nullptr;
  invocationReorder.rayTracingInvocationReorder = VK_TRUE;
}

std::span<const char* const> requiredDeviceExtensions() { return kRequiredExtensions; }

RequiredFeatures::RequiredFeatures() {
  vulkan12.sType = VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_2_FEATURES;
  vulkan12.pNext = &accelerationStructure;
  vulkan12.bufferDeviceAddress = VK_TRUE;
  vulkan12.descriptorIndexing = VK_TRUE;
  vulkan12.runtimeDescriptorArray = VK_TRUE;
  vulkan12.shaderSampledImageArrayNonUniformIndexing = VK_TRUE;
  vulkan12.scalarBlockLayout = VK_TRUE;
  vulkan12.descriptorBindingPartiallyBound = VK_TRUE;
  vulkan12.descriptorBindingVariableDescriptorCount = VK_TRUE;
  vulkan12.timelineSemaphore = VK_TRUE;  // the async dynamic BLAS builds signal one the engine waits on
  accelerationStructure.sType = VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_ACCELERATION_STRUCTURE_FEATURES_KHR;
  accelerationStructure.pNext = &rayTracingPipeline;
  accelerationStructure.accelerationStructure = VK_TRUE;
  rayTracingPipeline.sType = VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_RAY_TRACING_PIPELINE_FEATURES_KHR;
  rayTracingPipeline.pNext = nullptr;
  rayTracingPipeline.rayTracingPipeline = VK_TRUE;
  rayTracingPipeline.rayTracingPipelineTraceRaysIndirect = VK_TRUE;
}

void* RequiredFeatures::link(void* next) {
  rayTracingPipeline.pNext = next;
  return chainHead();
}

void RequiredFeatures::mergeVulkan12Into(VkPhysicalDeviceVulkan12Features& f) const {
  f.bufferDeviceAddress |= vulkan12.bufferDeviceAddress;
  f.descriptorIndexing |= vulkan12.descriptorIndexing;
  f.runtimeDescriptorArray |= vulkan12.runtimeDescriptorArray;
  f.shaderSampledImageArrayNonUniformIndexing |= vulkan12.shaderSampledImageArrayNonUniformIndexing;
  f.scalarBlockLayout |= vulkan12.scalarBlockLayout;
  f.descriptorBindingPartiallyBound |= vulkan12.descriptorBindingPartiallyBound;
  f.descriptorBindingVariableDescriptorCount |= vulkan12.descriptorBindingVariableDescriptorCount;
  f.timelineSemaphore |= vulkan12.timelineSemaphore;
}

const char* toString(ErrorCode code) {
  switch (code) {
    case ErrorCode::Ok: return "Ok";
    case ErrorCode::InvalidArgument: return "InvalidArgument";
    case ErrorCode::MissingExtension: return "MissingExtension";
    case ErrorCode::MissingFeature: return "MissingFeature";
    case ErrorCode::NoSuitableDevice: return "NoSuitableDevice";
    case ErrorCode::VulkanError: return "VulkanError";
    case ErrorCode::OutOfBudget: return "OutOfBudget";
    case ErrorCode::StaleHandle: return "StaleHandle";
    case ErrorCode::NotReady: return "NotReady";
    case ErrorCode::UnsupportedApiVersion: return "UnsupportedApiVersion";
  }
  return "Unknown";
}

const char* toString(MemoryCategory category) {
  switch (category) {
    case MemoryCategory::BlasStorage: return "blas_storage";
    case MemoryCategory::Scratch: return "scratch";
    case MemoryCategory::Tlas: return "tlas";
    case MemoryCategory::ShaderTables: return "shader_tables";
    case MemoryCategory::PassImages: return "pass_images";
    case MemoryCategory::PassBuffers: return "pass_buffers";
    case MemoryCategory::Count: break;
  }
  return "unknown";
}

Result<std::unique_ptr<Context>> Context::create(const ContextDesc& desc) {
  auto invalid = [](const std::string& m) { return Error{ErrorCode::InvalidArgument, VK_SUCCESS, m}; };
  if (!desc.instance) return invalid("ContextDesc::instance is VK_NULL_HANDLE; pass the engine's VkInstance");
  if (!desc.physicalDevice) {
    return invalid("ContextDesc::physicalDevice is VK_NULL_HANDLE; pass the engine's VkPhysicalDevice");
  }
  if (!desc.device) return invalid("ContextDesc::device is VK_NULL_HANDLE; pass the engine's VkDevice");
  if (!desc.getInstanceProcAddr) {
    return invalid("ContextDesc::getInstanceProcAddr is null; pass vkGetInstanceProcAddr of the engine's loader");
  }
  if (desc.framesInFlight > 8) {
    return invalid("ContextDesc::framesInFlight is " + std::to_string(desc.framesInFlight) + "; use 1..8 (0 = 2)");
  }
  if (desc.apiVersion != 0 && desc.apiVersion < kMinimumApiVersion) {
    return Error{ErrorCode::UnsupportedApiVersion, VK_SUCCESS,
                 "ContextDesc::apiVersion is Vulkan " + versionString(desc.apiVersion) +
                     "; Raybridge needs 1.2 or newer: create the instance with VkApplicationInfo::apiVersion = "
                     "VK_API_VERSION_1_2 (or newer) and pass the same value here"};
  }

  auto impl = std::make_unique<Impl>();
  impl->desc = desc;
  if (impl->desc.framesInFlight == 0) impl->desc.framesInFlight = 2;
  DeviceFunctions& vk = impl->vk;

  // Instance-level queries first, so a device without the extensions gets a message naming them rather than
  // one naming a missing function pointer.
  vk.vkGetPhysicalDeviceProperties2 = reinterpret_cast<PFN_vkGetPhysicalDeviceProperties2>(
      desc.getInstanceProcAddr(desc.instance, "vkGetPhysicalDeviceProperties2"));
  vk.vkGetPhysicalDeviceFeatures2 = reinterpret_cast<PFN_vkGetPhysicalDeviceFeatures2>(
      desc.getInstanceProcAddr(desc.instance, "vkGetPhysicalDeviceFeatures2"));
  vk.vkEnumerateDeviceExtensionProperties = reinterpret_cast<PFN_vkEnumerateDeviceExtensionProperties>(
      desc.getInstanceProcAddr(desc.instance, "vkEnumerateDeviceExtensionProperties"));
  if (!vk.vkGetPhysicalDeviceProperties2 || !vk.vkGetPhysicalDeviceFeatures2 ||
      !vk.vkEnumerateDeviceExtensionProperties) {
    return Error{ErrorCode::UnsupportedApiVersion, VK_SUCCESS,
                 "the instance does not expose the Vulkan 1.1 queries (vkGetPhysicalDeviceFeatures2), as an instance "
                 "created with VkApplicationInfo::apiVersion 1.0 does not: create it with apiVersion = "
                 "VK_API_VERSION_1_2 or newer (and pass it in ContextDesc::apiVersion)"};
  }

  VkPhysicalDeviceAccelerationStructurePropertiesKHR asProps{
      VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_ACCELERATION_STRUCTURE_PROPERTIES_KHR};
  VkPhysicalDeviceRayTracingPipelinePropertiesKHR rtProps{
      VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_RAY_TRACING_PIPELINE_PROPERTIES_KHR, &asProps};
  VkPhysicalDeviceDriverProperties driverProps{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_DRIVER_PROPERTIES, &rtProps};
  VkPhysicalDeviceProperties2 props{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_PROPERTIES_2, &driverProps};
  vk.vkGetPhysicalDeviceProperties2(desc.physicalDevice, &props);
  DeviceInfo& info = impl->info;
  info.deviceName = props.properties.deviceName;
  info.apiVersion = props.properties.apiVersion;
  if (VK_API_VERSION_MINOR(info.apiVersion) < 2 && VK_API_VERSION_MAJOR(info.apiVersion) == 1) {
    return Error{ErrorCode::MissingFeature, VK_SUCCESS,
                 "device '" + info.deviceName + "' supports Vulkan " +
                     std::to_string(VK_API_VERSION_MAJOR(info.apiVersion)) + "." +
                     std::to_string(VK_API_VERSION_MINOR(info.apiVersion)) + "; Raybridge needs Vulkan 1.2 or newer"};
  }
  // Enumerated once: the required extensions and the optional reorder extension are checked against the same list.
  const std::vector<VkExtensionProperties> extensions = deviceExtensions(vk, desc.physicalDevice);
  if (Status s = checkExtensions(extensions, info.deviceName); !s) return s.error();
  if (Status s = checkFeatures(vk, desc.physicalDevice, info.deviceName, desc.apiVersion); !s) return s.error();
  if (desc.invocationReorderEnabled) {
    if (Status s = checkInvocationReorder(vk, desc.physicalDevice, extensions, info.deviceName); !s) return s.error();
    VkPhysicalDeviceRayTracingInvocationReorderPropertiesNV serProps{
        VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_RAY_TRACING_INVOCATION_REORDER_PROPERTIES_NV};
    VkPhysicalDeviceProperties2 p2{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_PROPERTIES_2, &serProps};
    vk.vkGetPhysicalDeviceProperties2(desc.physicalDevice, &p2);
    info.invocationReorder = true;
    info.invocationReorderReorders = serProps.rayTracingInvocationReorderReorderingHint ==
                                     VK_RAY_TRACING_INVOCATION_REORDER_MODE_REORDER_NV;
  }

  if (const char* missing = loadDeviceFunctions(vk, desc.getInstanceProcAddr, desc.instance, desc.device)) {
    return Error{ErrorCode::MissingExtension, VK_SUCCESS,
                 std::string("Vulkan function ") + missing +
                     " could not be loaded from the engine's device: enable every extension in "
                     "rb::requiredDeviceExtensions() and the features of rb::RequiredFeatures when creating it"};
  }

  info.driverName = driverProps.driverName;
  info.driverInfo = driverProps.driverInfo;
  info.vendorId = props.properties.vendorID;
  info.isCpu = props.properties.deviceType == VK_PHYSICAL_DEVICE_TYPE_CPU;
  info.shaderGroupHandleSize = rtProps.shaderGroupHandleSize;
  info.shaderGroupHandleAlignment = rtProps.shaderGroupHandleAlignment;
  info.shaderGroupBaseAlignment = rtProps.shaderGroupBaseAlignment;
  info.maxRayRecursionDepth = rtProps.maxRayRecursionDepth;
  info.minAccelerationStructureScratchOffsetAlignment = asProps.minAccelerationStructureScratchOffsetAlignment;
  info.maxPrimitiveCount = asProps.maxPrimitiveCount;
  info.maxInstanceCount = asProps.maxInstanceCount;
  info.timestampPeriodNs = props.properties.limits.timestampPeriod;
  vk.vkGetPhysicalDeviceMemoryProperties(desc.physicalDevice, &impl->memoryProperties);
  uint32_t familyCount = 0;
  vk.vkGetPhysicalDeviceQueueFamilyProperties(desc.physicalDevice, &familyCount, nullptr);
  std::vector<VkQueueFamilyProperties> families(familyCount);
  vk.vkGetPhysicalDeviceQueueFamilyProperties(desc.physicalDevice, &familyCount, families.data());
  if (desc.mainQueueFamily >= familyCount) {
    return invalid("ContextDesc::mainQueueFamily " + std::to_string(desc.mainQueueFamily) +
                   " is not a queue family of '" + info.deviceName + "' (it has " + std::to_string(familyCount) + ")");
  }
  info.timestampValidBits = families[desc.mainQueueFamily].timestampValidBits;
  info.timestampsSupported = info.timestampValidBits != 0 && props.properties.limits.timestampPeriod > 0.0f;

  return std::unique_ptr<Context>(new Context(std::move(impl)));
}

Context::Context(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}

// Contract (context.h): the GPU is done, so whatever is still retired goes now.
Context::~Context() { impl_->releaseRetired(/*deviceIdle=*/true); }

void Context::beginFrame() {
  ++impl_->frame;
  impl_->releaseRetired(false);
}

void Context::releaseAfterIdle() {
  impl_->idleSeen = true;
  impl_->idleThrough = impl_->frame;
  impl_->releaseRetired(true);
}

uint64_t Context::frameIndex() const { return impl_->frame; }
uint32_t Context::framesInFlight() const { return impl_->desc.framesInFlight; }
const DeviceInfo& Context::deviceInfo() const { return impl_->info; }
VkDevice Context::device() const { return impl_->desc.device; }
VkPhysicalDevice Context::physicalDevice() const { return impl_->desc.physicalDevice; }
MemoryStats Context::memoryStats() const { return impl_->memory; }
namespace internal {
const DeviceFunctions& deviceFunctions(const Context& ctx) { return ContextAccess::impl(ctx).vk; }
}  // namespace internal

void Context::Impl::releaseRetired(bool deviceIdle) {
  // Released in retirement order: a later release may depend on an earlier one still existing.
  std::vector<PendingRelease> keep;
  std::vector<PendingRelease> due;
  for (PendingRelease& p : pendingReleases) {
    if (deviceIdle || p.frame + desc.framesInFlight <= frame) {
      due.push_back(std::move(p));
    } else {
      keep.push_back(std::move(p));
    }
  }
  pendingReleases = std::move(keep);
  for (PendingRelease& p : due) p.release();
}

int32_t Context::Impl::findMemoryType(uint32_t typeBits, VkMemoryPropertyFlags required,
                                      VkMemoryPropertyFlags preferred) const {
  int32_t fallback = -1;
  for (uint32_t i = 0; i < memoryProperties.memoryTypeCount; ++i) {
    if (!(typeBits & (1u << i))) continue;
    VkMemoryPropertyFlags flags = memoryProperties.memoryTypes[i].propertyFlags;
    if ((flags & required) != required) continue;
    if ((flags & preferred) == preferred) return static_cast<int32_t>(i);
    if (fallback < 0) fallback = static_cast<int32_t>(i);
  }
  return fallback;
}

}  // namespace rb
