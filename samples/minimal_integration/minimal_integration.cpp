// minimal_integration: Raybridge in a bare Vulkan program, independent of the sample engine and of
// rb::HeadlessDevice. It creates its own instance (volk loads Vulkan), device and queue, rasterizes its own
// G-buffer with dynamic rendering — reversed-Z D32 depth with an infinite far plane, octahedral normals
// (rbEncodeOctahedral from shaders/public/raybridge_gbuffer.glsl) and motion vectors of a moving camera — describes
// it as an rb::GBufferDesc and lets rb::HybridEffects (preset Low: hard shadows, 4-ray AO, denoised) trace
// into its own command buffers, two frames in flight. What it proves: the public headers are enough to
// integrate. main() takes the steps of the quick start (docs/quickstart.md) in order: (1) device, (2) context,
// (3) meshes, (4) G-buffer, (5) effects, (6) frames, (7) outputs.
//
//   minimal_integration [--out DIR] [--width W] [--height H] [--frames N] [--validate]
//
// Writes into DIR, for the last frame: depth.pfm (raw reversed-Z depth, 0 = sky), shadow.pfm and ao.pfm (the
// front end's outputs, 1 = lit / open), motion.pfm (pixels, current - previous, in r and g), composite.png
// and camera.txt (the matrices the frame was drawn with). PFM rows run bottom to top, as the format says.
// Validation (VK_LAYER_KHRONOS_validation with synchronization validation) is on with --validate or
// RAYBRIDGE_VALIDATION=1. Exit status: 0 = ok, 1 = a Vulkan or Raybridge error, 2 = validation errors.
#include <volk.h>

#include <raybridge/raybridge.h>

#include <CLI/CLI.hpp>

#define STB_IMAGE_WRITE_IMPLEMENTATION
#include <stb/stb_image_write.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "minimal_integration_shaders.h"
#include "minimal_scene.h"

namespace {

constexpr uint32_t kFramesInFlight = 2;
// VkApplicationInfo::apiVersion of the instance, handed to Raybridge as ContextDesc::apiVersion. 1.3 for the
// program's own dynamic rendering; Raybridge alone needs rb::kMinimumApiVersion (1.2).
constexpr uint32_t kApiVersion = VK_API_VERSION_1_3;
static_assert(kApiVersion >= rb::kMinimumApiVersion);

struct Options {
  std::string outDir = "minimal_out";
  uint32_t width = 640, height = 360, frames = 4;
  bool validate = false;
};

// ---- Errors: any Vulkan or Raybridge failure ends the program with status 1.

[[noreturn]] void fail(const std::string& what) {
  std::fprintf(stderr, "minimal_integration: %s\n", what.c_str());
  std::exit(1);
}
void check(VkResult r, const char* what) {
  if (r != VK_SUCCESS) fail(std::string(what) + " failed with VkResult " + std::to_string(int(r)));
}
// Raybridge's what() names the bad field and the fix. Checking ok() first lets the program say which of its calls
// failed and exit with its own status (value() on an error prints the message too, but aborts).
void check(const rb::Status& s, const char* call) {
  if (!s) fail(std::string(call) + ": " + s.what());
}
template <typename T>
T check(rb::Result<T> r, const char* call) {
  if (!r) fail(std::string(call) + ": " + r.what());
  return std::move(r).value();
}

// ---- (1) The device: the program owns it and hands it to Raybridge.

struct Gpu {
  VkInstance instance = VK_NULL_HANDLE;
  VkDebugUtilsMessengerEXT messenger = VK_NULL_HANDLE;
  VkPhysicalDevice physicalDevice = VK_NULL_HANDLE;
  VkPhysicalDeviceMemoryProperties memory{};
  VkDevice device = VK_NULL_HANDLE;
  uint32_t queueFamily = 0;
  VkQueue queue = VK_NULL_HANDLE;
  uint32_t validationErrors = 0;  // counted by onMessage
};

VKAPI_ATTR VkBool32 VKAPI_CALL onMessage(VkDebugUtilsMessageSeverityFlagBitsEXT severity,
                                         VkDebugUtilsMessageTypeFlagsEXT,
                                         const VkDebugUtilsMessengerCallbackDataEXT* data, void* errors) {
  if (severity & VK_DEBUG_UTILS_MESSAGE_SEVERITY_ERROR_BIT_EXT) {
    ++*static_cast<uint32_t*>(errors);
    std::fprintf(stderr, "[validation] %s\n", data->pMessage);
  }
  return VK_FALSE;
}

// With validation, synchronization validation and a messenger that also sees the instance's own creation.
void createInstance(Gpu& gpu, bool validate) {
  check(volkInitialize(), "volkInitialize (is the Vulkan loader installed?)");
  VkApplicationInfo app{VK_STRUCTURE_TYPE_APPLICATION_INFO, nullptr, "minimal_integration", 1, nullptr, 0, kApiVersion};
  VkDebugUtilsMessengerCreateInfoEXT messengerInfo{VK_STRUCTURE_TYPE_DEBUG_UTILS_MESSENGER_CREATE_INFO_EXT};
  messengerInfo.messageSeverity = VK_DEBUG_UTILS_MESSAGE_SEVERITY_ERROR_BIT_EXT;
  messengerInfo.messageType = VK_DEBUG_UTILS_MESSAGE_TYPE_GENERAL_BIT_EXT |
                              VK_DEBUG_UTILS_MESSAGE_TYPE_VALIDATION_BIT_EXT;
  messengerInfo.pfnUserCallback = &onMessage;
  messengerInfo.pUserData = &gpu.validationErrors;
  const VkValidationFeatureEnableEXT syncValidation = VK_VALIDATION_FEATURE_ENABLE_SYNCHRONIZATION_VALIDATION_EXT;
  VkValidationFeaturesEXT features{VK_STRUCTURE_TYPE_VALIDATION_FEATURES_EXT, &messengerInfo, 1, &syncValidation};
  const char* layer = "VK_LAYER_KHRONOS_validation";
  const char* debugUtils = VK_EXT_DEBUG_UTILS_EXTENSION_NAME;
  VkInstanceCreateInfo info{VK_STRUCTURE_TYPE_INSTANCE_CREATE_INFO,
                            validate ? &features : nullptr,
                            0,
                            &app,
                            validate ? 1u : 0u,
                            &layer,
                            validate ? 1u : 0u,
                            &debugUtils};
  check(vkCreateInstance(&info, nullptr, &gpu.instance),
        validate ? "vkCreateInstance with VK_LAYER_KHRONOS_validation" : "vkCreateInstance");
  volkLoadInstanceOnly(gpu.instance);
  if (validate)
    check(vkCreateDebugUtilsMessengerEXT(gpu.instance, &messengerInfo, nullptr, &gpu.messenger), "messenger");
}

bool hasExtensions(VkPhysicalDevice device, std::span<const char* const> names) {
  uint32_t count = 0;
  vkEnumerateDeviceExtensionProperties(device, nullptr, &count, nullptr);
  std::vector<VkExtensionProperties> available(count);
  vkEnumerateDeviceExtensionProperties(device, nullptr, &count, available.data());
  return std::all_of(names.begin(), names.end(), [&](const char* name) {
    return std::any_of(available.begin(), available.end(),
                       [&](const VkExtensionProperties& e) { return std::strcmp(e.extensionName, name) == 0; });
  });
}

// The first device with the program's Vulkan version, Raybridge's extensions and a graphics queue.
void pickPhysicalDevice(Gpu& gpu) {
  uint32_t count = 0;
  vkEnumeratePhysicalDevices(gpu.instance, &count, nullptr);
  std::vector<VkPhysicalDevice> devices(count);
  vkEnumeratePhysicalDevices(gpu.instance, &count, devices.data());
  for (VkPhysicalDevice candidate : devices) {
    VkPhysicalDeviceProperties properties;
    vkGetPhysicalDeviceProperties(candidate, &properties);
    if (properties.apiVersion < kApiVersion || !hasExtensions(candidate, rb::requiredDeviceExtensions())) continue;
    vkGetPhysicalDeviceQueueFamilyProperties(candidate, &count, nullptr);
    std::vector<VkQueueFamilyProperties> families(count);
    vkGetPhysicalDeviceQueueFamilyProperties(candidate, &count, families.data());
    for (uint32_t i = 0; i < count; ++i) {
      if (families[i].queueFlags & VK_QUEUE_GRAPHICS_BIT) {
        gpu.physicalDevice = candidate, gpu.queueFamily = i;
        vkGetPhysicalDeviceMemoryProperties(candidate, &gpu.memory);
        return;
      }
    }
  }
  fail("no Vulkan 1.3 device supports ray tracing pipelines (lavapipe needs Mesa 25)");
}

// Raybridge's extensions, and its features (rb::RequiredFeatures) chained ahead of the program's own.
void createDevice(Gpu& gpu) {
  rb::RequiredFeatures required;
  VkPhysicalDeviceVulkan13Features v13{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_3_FEATURES};
  v13.dynamicRendering = VK_TRUE;
  const float priority = 1.0f;
  VkDeviceQueueCreateInfo queue{VK_STRUCTURE_TYPE_DEVICE_QUEUE_CREATE_INFO, nullptr, 0, gpu.queueFamily, 1, &priority};
  const std::span<const char* const> extensions = rb::requiredDeviceExtensions();
  VkDeviceCreateInfo info{VK_STRUCTURE_TYPE_DEVICE_CREATE_INFO, required.link(&v13), 0, 1, &queue, 0, nullptr,
                          uint32_t(extensions.size()),          extensions.data()};
  check(vkCreateDevice(gpu.physicalDevice, &info, nullptr, &gpu.device), "vkCreateDevice");
  volkLoadDevice(gpu.device);
  vkGetDeviceQueue(gpu.device, gpu.queueFamily, 0, &gpu.queue);
}

uint32_t memoryType(const Gpu& gpu, uint32_t typeBits, VkMemoryPropertyFlags want) {
  for (uint32_t i = 0; i < gpu.memory.memoryTypeCount; ++i) {
    if ((typeBits & (1u << i)) && (gpu.memory.memoryTypes[i].propertyFlags & want) == want) return i;
  }
  fail("no suitable memory type");
}

// Host-visible buffers: the scene is written in place, so no upload submission (and no wait) is needed.
struct Buffer {
  VkBuffer buffer = VK_NULL_HANDLE;
  VkDeviceMemory memory = VK_NULL_HANDLE;
  VkDeviceAddress address = 0;
  void* mapped = nullptr;
};
Buffer makeBuffer(const Gpu& gpu, VkDeviceSize size, VkBufferUsageFlags usage, const void* data = nullptr) {
  Buffer b;
  VkBufferCreateInfo info{VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO, nullptr, 0, size, usage};
  check(vkCreateBuffer(gpu.device, &info, nullptr, &b.buffer), "vkCreateBuffer");
  VkMemoryRequirements req;
  vkGetBufferMemoryRequirements(gpu.device, b.buffer, &req);
  VkMemoryAllocateFlagsInfo flags{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_FLAGS_INFO, nullptr,
                                  VK_MEMORY_ALLOCATE_DEVICE_ADDRESS_BIT};
  const bool addressable = usage & VK_BUFFER_USAGE_SHADER_DEVICE_ADDRESS_BIT;
  VkMemoryAllocateInfo alloc{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO, addressable ? &flags : nullptr, req.size,
                             memoryType(gpu, req.memoryTypeBits,
                                        VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT | VK_MEMORY_PROPERTY_HOST_COHERENT_BIT)};
  check(vkAllocateMemory(gpu.device, &alloc, nullptr, &b.memory), "vkAllocateMemory");
  check(vkBindBufferMemory(gpu.device, b.buffer, b.memory, 0), "vkBindBufferMemory");
  check(vkMapMemory(gpu.device, b.memory, 0, VK_WHOLE_SIZE, 0, &b.mapped), "vkMapMemory");
  if (data) std::memcpy(b.mapped, data, size);
  VkBufferDeviceAddressInfo addressInfo{VK_STRUCTURE_TYPE_BUFFER_DEVICE_ADDRESS_INFO, nullptr, b.buffer};
  if (addressable) b.address = vkGetBufferDeviceAddress(gpu.device, &addressInfo);
  return b;
}
void destroy(const Gpu& gpu, const Buffer& b) {
  vkDestroyBuffer(gpu.device, b.buffer, nullptr);
  vkFreeMemory(gpu.device, b.memory, nullptr);
}

// ---- (3) The meshes: the program's own buffers, registered with Raybridge in place.

// Vertex and index buffers of the raster pass and BLAS inputs at once (no copy, no upload).
struct Scene {
  std::vector<minimal::Mesh> meshes;
  std::vector<Buffer> vertexBuffers, indexBuffers;
  std::vector<rb::Instance> instances;
};

Scene createScene(const Gpu& gpu, rb::AccelerationStructureService& service) {
  Scene scene{.meshes = minimal::makeScene()};
  const VkBufferUsageFlags geometry = VK_BUFFER_USAGE_SHADER_DEVICE_ADDRESS_BIT |
                                      VK_BUFFER_USAGE_ACCELERATION_STRUCTURE_BUILD_INPUT_READ_ONLY_BIT_KHR;
  for (const minimal::Mesh& m : scene.meshes) {
    const VkDeviceSize vBytes = m.positions.size() * sizeof(float), iBytes = m.indices.size() * sizeof(uint32_t);
    const Buffer& vertices = scene.vertexBuffers.emplace_back(
        makeBuffer(gpu, vBytes, geometry | VK_BUFFER_USAGE_VERTEX_BUFFER_BIT, m.positions.data()));
    const Buffer& indices = scene.indexBuffers.emplace_back(
        makeBuffer(gpu, iBytes, geometry | VK_BUFFER_USAGE_INDEX_BUFFER_BIT, m.indices.data()));
    // The host copies let Raybridge share one BLAS between identical meshes; the build itself is only queued.
    const rb::MeshDesc desc{.vertexAddress = vertices.address,
                            .vertexBufferBytes = vBytes,
                            .vertexCount = uint32_t(m.positions.size() / 3),
                            .indexAddress = indices.address,
                            .indexBufferBytes = iBytes,
                            .triangleCount = uint32_t(m.indices.size() / 3),
                            .hostVertices = m.positions.data(),
                            .hostIndices = m.indices.data(),
                            .debugName = m.name};
    // Identity transform: the meshes are in world space.
    scene.instances.push_back(rb::Instance{.mesh = check(service.registerMesh(desc), "registerMesh")});
  }
  return scene;
}

void destroy(const Gpu& gpu, const Scene& scene) {
  for (const Buffer& b : scene.vertexBuffers) destroy(gpu, b);
  for (const Buffer& b : scene.indexBuffers) destroy(gpu, b);
}

// ---- (4) The G-buffer: the program's images and pipeline, and the rb::GBufferDesc that describes them.

// The matrices a frame is drawn with (column-major): this frame's camera and, for the motion vectors, the
// previous frame's.
struct Camera {
  double eye[3] = {};
  float view[16] = {}, projection[16] = {}, previousView[16] = {};
  // gbuffer.vert's push constants: viewProjection, then previousPixelFromWorld (the previous clip space in pixels).
  float pushConstants[32] = {};
};

Camera cameraOfFrame(uint32_t frame, uint32_t width, uint32_t height) {
  Camera c;
  double target[3];
  minimal::reversedInfiniteProjection(minimal::kFovYDegrees, float(width) / float(height), minimal::kNearPlane,
                                      c.projection);
  minimal::cameraAt(frame ? frame - 1 : 0, c.eye, target);
  minimal::viewMatrix(c.eye, target, c.previousView);
  minimal::cameraAt(frame, c.eye, target);
  minimal::viewMatrix(c.eye, target, c.view);
  const float toPixels[16] = {width * 0.5f,  0, 0, 0, 0, height * 0.5f, 0, 0, 0, 0, 1, 0, width * 0.5f,
                              height * 0.5f, 0, 1};
  float previousClip[16];
  minimal::multiply(c.projection, c.view, c.pushConstants);
  minimal::multiply(c.projection, c.previousView, previousClip);
  minimal::multiply(toPixels, previousClip, c.pushConstants + 16);
  return c;
}

struct Image {
  VkImage image = VK_NULL_HANDLE;
  VkDeviceMemory memory = VK_NULL_HANDLE;
  VkImageView view = VK_NULL_HANDLE;
  VkFormat format = VK_FORMAT_UNDEFINED;
  VkImageUsageFlags usage = 0;  // as created: what GBufferImage::usage states
  VkImageAspectFlags aspect = 0;
};

// Sampled for Raybridge's passes, a transfer source for the read-back.
Image makeImage(const Gpu& gpu, uint32_t w, uint32_t h, VkFormat format, VkImageUsageFlags attachmentUsage,
                VkImageAspectFlags aspect) {
  VkFormatProperties props;
  vkGetPhysicalDeviceFormatProperties(gpu.physicalDevice, format, &props);
  const VkFormatFeatureFlags attachment = aspect == VK_IMAGE_ASPECT_DEPTH_BIT
                                              ? VK_FORMAT_FEATURE_DEPTH_STENCIL_ATTACHMENT_BIT
                                              : VK_FORMAT_FEATURE_COLOR_ATTACHMENT_BIT;
  if ((props.optimalTilingFeatures & attachment) == 0)
    fail("format " + std::to_string(format) + " cannot be rendered to");
  Image img{.format = format,
            .usage = attachmentUsage | VK_IMAGE_USAGE_SAMPLED_BIT | VK_IMAGE_USAGE_TRANSFER_SRC_BIT,
            .aspect = aspect};
  VkImageCreateInfo info{VK_STRUCTURE_TYPE_IMAGE_CREATE_INFO};
  info.imageType = VK_IMAGE_TYPE_2D;
  info.format = format;
  info.extent = {w, h, 1};
  info.mipLevels = info.arrayLayers = 1;
  info.samples = VK_SAMPLE_COUNT_1_BIT;
  info.usage = img.usage;
  check(vkCreateImage(gpu.device, &info, nullptr, &img.image), "vkCreateImage");
  VkMemoryRequirements req;
  vkGetImageMemoryRequirements(gpu.device, img.image, &req);
  VkMemoryAllocateInfo alloc{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO, nullptr, req.size,
                             memoryType(gpu, req.memoryTypeBits, VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT)};
  check(vkAllocateMemory(gpu.device, &alloc, nullptr, &img.memory), "vkAllocateMemory");
  check(vkBindImageMemory(gpu.device, img.image, img.memory, 0), "vkBindImageMemory");
  VkImageViewCreateInfo view{VK_STRUCTURE_TYPE_IMAGE_VIEW_CREATE_INFO,
                             nullptr,
                             0,
                             img.image,
                             VK_IMAGE_VIEW_TYPE_2D,
                             format,
                             {},
                             {aspect, 0, 1, 0, 1}};
  check(vkCreateImageView(gpu.device, &view, nullptr, &img.view), "vkCreateImageView");
  return img;
}

// One set of images, reused every frame, and the pipeline that rasterises into them.
struct GBuffer {
  uint32_t width = 0, height = 0;
  Image depth, normal, motion;  // reversed-Z D32, octahedral normals in RG16_SNORM, pixel motion in RG16_SFLOAT
  VkShaderModule modules[2] = {};
  VkPipelineLayout layout = VK_NULL_HANDLE;
  VkPipeline pipeline = VK_NULL_HANDLE;
};

// The shaders (embedded SPIR-V) and a layout with two matrices as push constants.
void createGBufferLayout(const Gpu& gpu, GBuffer& g) {
  const std::span<const uint32_t> code[2] = {minimal::spirv::gbuffer_vert, minimal::spirv::gbuffer_frag};
  for (int i = 0; i < 2; ++i) {
    VkShaderModuleCreateInfo info{VK_STRUCTURE_TYPE_SHADER_MODULE_CREATE_INFO, nullptr, 0, code[i].size_bytes(),
                                  code[i].data()};
    check(vkCreateShaderModule(gpu.device, &info, nullptr, &g.modules[i]), "vkCreateShaderModule");
  }
  VkPushConstantRange pushRange{VK_SHADER_STAGE_VERTEX_BIT, 0, sizeof Camera::pushConstants};
  VkPipelineLayoutCreateInfo layoutInfo{
      VK_STRUCTURE_TYPE_PIPELINE_LAYOUT_CREATE_INFO, nullptr, 0, 0, nullptr, 1, &pushRange};
  check(vkCreatePipelineLayout(gpu.device, &layoutInfo, nullptr, &g.layout), "vkCreatePipelineLayout");
}

// Dynamic rendering, depth test GREATER against a clear of 0 (reversed-Z).
void createGBufferPipeline(const Gpu& gpu, GBuffer& g) {
  VkPipelineShaderStageCreateInfo stages[2] = {{VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO, nullptr, 0,
                                                VK_SHADER_STAGE_VERTEX_BIT, g.modules[0], "main"},
                                               {VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO, nullptr, 0,
                                                VK_SHADER_STAGE_FRAGMENT_BIT, g.modules[1], "main"}};
  VkVertexInputBindingDescription binding{0, 3 * sizeof(float), VK_VERTEX_INPUT_RATE_VERTEX};
  VkVertexInputAttributeDescription attribute{0, 0, VK_FORMAT_R32G32B32_SFLOAT, 0};
  VkPipelineVertexInputStateCreateInfo vertexInput{
      VK_STRUCTURE_TYPE_PIPELINE_VERTEX_INPUT_STATE_CREATE_INFO, nullptr, 0, 1, &binding, 1, &attribute};
  VkPipelineInputAssemblyStateCreateInfo assembly{VK_STRUCTURE_TYPE_PIPELINE_INPUT_ASSEMBLY_STATE_CREATE_INFO, nullptr,
                                                  0, VK_PRIMITIVE_TOPOLOGY_TRIANGLE_LIST};
  VkViewport viewport{0, 0, float(g.width), float(g.height), 0, 1};
  VkRect2D scissor{{0, 0}, {g.width, g.height}};
  VkPipelineViewportStateCreateInfo viewportState{
      VK_STRUCTURE_TYPE_PIPELINE_VIEWPORT_STATE_CREATE_INFO, nullptr, 0, 1, &viewport, 1, &scissor};
  VkPipelineRasterizationStateCreateInfo raster{VK_STRUCTURE_TYPE_PIPELINE_RASTERIZATION_STATE_CREATE_INFO};
  raster.cullMode = VK_CULL_MODE_NONE;
  raster.lineWidth = 1.0f;
  VkPipelineMultisampleStateCreateInfo multisample{VK_STRUCTURE_TYPE_PIPELINE_MULTISAMPLE_STATE_CREATE_INFO, nullptr, 0,
                                                   VK_SAMPLE_COUNT_1_BIT};
  VkPipelineDepthStencilStateCreateInfo depthState{.sType = VK_STRUCTURE_TYPE_PIPELINE_DEPTH_STENCIL_STATE_CREATE_INFO,
                                                   .depthTestEnable = VK_TRUE,
                                                   .depthWriteEnable = VK_TRUE,
                                                   .depthCompareOp = VK_COMPARE_OP_GREATER};  // reversed-Z
  VkPipelineColorBlendAttachmentState blend[2] = {{}, {}};
  blend[0].colorWriteMask = blend[1].colorWriteMask = VK_COLOR_COMPONENT_R_BIT | VK_COLOR_COMPONENT_G_BIT;
  VkPipelineColorBlendStateCreateInfo blendState{.sType = VK_STRUCTURE_TYPE_PIPELINE_COLOR_BLEND_STATE_CREATE_INFO,
                                                 .attachmentCount = 2,
                                                 .pAttachments = blend};
  const VkFormat colorFormats[2] = {g.normal.format, g.motion.format};
  VkPipelineRenderingCreateInfo rendering{
      VK_STRUCTURE_TYPE_PIPELINE_RENDERING_CREATE_INFO, nullptr, 0, 2, colorFormats, g.depth.format};
  const VkGraphicsPipelineCreateInfo info{.sType = VK_STRUCTURE_TYPE_GRAPHICS_PIPELINE_CREATE_INFO,
                                          .pNext = &rendering,
                                          .stageCount = 2,
                                          .pStages = stages,
                                          .pVertexInputState = &vertexInput,
                                          .pInputAssemblyState = &assembly,
                                          .pViewportState = &viewportState,
                                          .pRasterizationState = &raster,
                                          .pMultisampleState = &multisample,
                                          .pDepthStencilState = &depthState,
                                          .pColorBlendState = &blendState,
                                          .layout = g.layout};
  check(vkCreateGraphicsPipelines(gpu.device, VK_NULL_HANDLE, 1, &info, nullptr, &g.pipeline), "G-buffer pipeline");
}

GBuffer createGBuffer(const Gpu& gpu, uint32_t width, uint32_t height) {
  GBuffer g{.width = width, .height = height};
  g.depth = makeImage(gpu, width, height, VK_FORMAT_D32_SFLOAT, VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT,
                      VK_IMAGE_ASPECT_DEPTH_BIT);
  g.normal = makeImage(gpu, width, height, VK_FORMAT_R16G16_SNORM, VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT,
                       VK_IMAGE_ASPECT_COLOR_BIT);
  g.motion = makeImage(gpu, width, height, VK_FORMAT_R16G16_SFLOAT, VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT,
                       VK_IMAGE_ASPECT_COLOR_BIT);
  createGBufferLayout(gpu, g);
  createGBufferPipeline(gpu, g);
  return g;
}

void destroy(const Gpu& gpu, const GBuffer& g) {
  vkDestroyPipeline(gpu.device, g.pipeline, nullptr);
  vkDestroyPipelineLayout(gpu.device, g.layout, nullptr);
  for (VkShaderModule m : g.modules) vkDestroyShaderModule(gpu.device, m, nullptr);
  for (const Image* img : {&g.depth, &g.normal, &g.motion}) {
    vkDestroyImageView(gpu.device, img->view, nullptr);
    vkDestroyImage(gpu.device, img->image, nullptr);
    vkFreeMemory(gpu.device, img->memory, nullptr);
  }
}

// The G-buffer contract Raybridge reads (gbuffer.h). GBufferImage::usage and ::aspectMask are optional, but the
// program knows them: stated, Raybridge checks them before it records anything.
rb::GBufferDesc describeGBuffer(const GBuffer& g, const Camera& camera) {
  auto image = [](const Image& i) {
    return rb::GBufferImage{
        .view = i.view, .layout = VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL, .usage = i.usage, .aspectMask = i.aspect};
  };
  rb::GBufferDesc desc{.width = g.width,
                       .height = g.height,
                       .depth = image(g.depth),
                       .depthConvention = rb::DepthConvention::ReversedZ,
                       .depthFormat = g.depth.format,
                       .normal = image(g.normal),
                       .normalEncoding = rb::NormalEncoding::Octahedral,
                       .motionVectors = image(g.motion)};
  std::memcpy(desc.view, camera.view, sizeof camera.view);
  std::memcpy(desc.projection, camera.projection, sizeof camera.projection);
  std::memcpy(desc.cameraPosition, camera.eye, sizeof camera.eye);
  return desc;
}

// ---- (6) Frames: a command buffer and a fence per slot, the G-buffer pass and the hand-over barrier.

// Every transition here but the hand-over waits for all earlier work: obviously correct over minimal.
void transition(VkCommandBuffer cmd, VkImage image, VkImageAspectFlags aspect, VkImageLayout from, VkImageLayout to,
                VkPipelineStageFlags dstStage, VkAccessFlags dstAccess) {
  VkImageMemoryBarrier b{VK_STRUCTURE_TYPE_IMAGE_MEMORY_BARRIER,
                         nullptr,
                         VK_ACCESS_MEMORY_WRITE_BIT,
                         dstAccess,
                         from,
                         to,
                         VK_QUEUE_FAMILY_IGNORED,
                         VK_QUEUE_FAMILY_IGNORED,
                         image,
                         {aspect, 0, 1, 0, 1}};
  vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_ALL_COMMANDS_BIT, dstStage, 0, 0, nullptr, 0, nullptr, 1, &b);
}

// The previous frame's passes have read the images (the transitions wait for them); their contents are discarded.
void rasterGBuffer(VkCommandBuffer cmd, const GBuffer& g, const Scene& scene, const Camera& camera) {
  transition(cmd, g.depth.image, g.depth.aspect, VK_IMAGE_LAYOUT_UNDEFINED, VK_IMAGE_LAYOUT_DEPTH_ATTACHMENT_OPTIMAL,
             VK_PIPELINE_STAGE_EARLY_FRAGMENT_TESTS_BIT | VK_PIPELINE_STAGE_LATE_FRAGMENT_TESTS_BIT,
             VK_ACCESS_DEPTH_STENCIL_ATTACHMENT_READ_BIT | VK_ACCESS_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT);
  for (const Image* img : {&g.normal, &g.motion}) {
    transition(cmd, img->image, img->aspect, VK_IMAGE_LAYOUT_UNDEFINED, VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL,
               VK_PIPELINE_STAGE_COLOR_ATTACHMENT_OUTPUT_BIT, VK_ACCESS_COLOR_ATTACHMENT_WRITE_BIT);
  }
  VkRenderingAttachmentInfo colors[2] = {{VK_STRUCTURE_TYPE_RENDERING_ATTACHMENT_INFO},
                                         {VK_STRUCTURE_TYPE_RENDERING_ATTACHMENT_INFO}};
  colors[0].imageView = g.normal.view;
  colors[1].imageView = g.motion.view;
  for (VkRenderingAttachmentInfo& c : colors) {
    c.imageLayout = VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL;
    c.loadOp = VK_ATTACHMENT_LOAD_OP_CLEAR;
    c.storeOp = VK_ATTACHMENT_STORE_OP_STORE;
  }
  VkRenderingAttachmentInfo depth = colors[0];
  depth.imageView = g.depth.view;
  depth.imageLayout = VK_IMAGE_LAYOUT_DEPTH_ATTACHMENT_OPTIMAL;
  depth.clearValue.depthStencil = {0.0f, 0};  // reversed-Z: far (infinity) is 0
  const VkRect2D area{{0, 0}, {g.width, g.height}};
  VkRenderingInfo rendering{VK_STRUCTURE_TYPE_RENDERING_INFO, nullptr, 0, area, 1, 0, 2, colors, &depth};
  vkCmdBeginRendering(cmd, &rendering);
  vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, g.pipeline);
  vkCmdPushConstants(cmd, g.layout, VK_SHADER_STAGE_VERTEX_BIT, 0, sizeof camera.pushConstants, camera.pushConstants);
  for (size_t i = 0; i < scene.meshes.size(); ++i) {
    const VkDeviceSize zero = 0;
    vkCmdBindVertexBuffers(cmd, 0, 1, &scene.vertexBuffers[i].buffer, &zero);
    vkCmdBindIndexBuffer(cmd, scene.indexBuffers[i].buffer, 0, VK_INDEX_TYPE_UINT32);
    vkCmdDrawIndexed(cmd, uint32_t(scene.meshes[i].indices.size()), 1, 0, 0, 0);
  }
  vkCmdEndRendering(cmd);
}

// The one barrier between the G-buffer pass and Raybridge, as gbuffer.h documents it: the attachments' writes made
// available to, and visible at, ray tracing and compute shader reads, in SHADER_READ_ONLY_OPTIMAL. The meshes'
// buffers need none: the host wrote them (coherent memory) before the submission, which makes them visible.
void handOverGBuffer(VkCommandBuffer cmd, const GBuffer& g) {
  VkImageMemoryBarrier barriers[3];
  const Image* images[3] = {&g.depth, &g.normal, &g.motion};
  for (int i = 0; i < 3; ++i) {
    const bool depth = images[i] == &g.depth;
    barriers[i] = {
        .sType = VK_STRUCTURE_TYPE_IMAGE_MEMORY_BARRIER,
        .srcAccessMask = depth ? VK_ACCESS_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT : VK_ACCESS_COLOR_ATTACHMENT_WRITE_BIT,
        .dstAccessMask = VK_ACCESS_SHADER_READ_BIT,
        .oldLayout = depth ? VK_IMAGE_LAYOUT_DEPTH_ATTACHMENT_OPTIMAL : VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL,
        .newLayout = VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL,
        .srcQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED,
        .dstQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED,
        .image = images[i]->image,
        .subresourceRange = {images[i]->aspect, 0, 1, 0, 1}};
  }
  vkCmdPipelineBarrier(cmd,
                       VK_PIPELINE_STAGE_EARLY_FRAGMENT_TESTS_BIT | VK_PIPELINE_STAGE_LATE_FRAGMENT_TESTS_BIT |
                           VK_PIPELINE_STAGE_COLOR_ATTACHMENT_OUTPUT_BIT,
                       VK_PIPELINE_STAGE_RAY_TRACING_SHADER_BIT_KHR | VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, 0, 0,
                       nullptr, 0, nullptr, 3, barriers);
}

// The slot's fence guards its command buffer and Context::beginFrame's contract.
struct Frames {
  VkCommandPool pool = VK_NULL_HANDLE;
  VkCommandBuffer cmds[kFramesInFlight] = {};
  VkFence fences[kFramesInFlight] = {};
};

Frames createFrames(const Gpu& gpu) {
  Frames f;
  VkCommandPoolCreateInfo poolInfo{VK_STRUCTURE_TYPE_COMMAND_POOL_CREATE_INFO, nullptr,
                                   VK_COMMAND_POOL_CREATE_RESET_COMMAND_BUFFER_BIT, gpu.queueFamily};
  check(vkCreateCommandPool(gpu.device, &poolInfo, nullptr, &f.pool), "vkCreateCommandPool");
  VkCommandBufferAllocateInfo cmdInfo{VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO, nullptr, f.pool,
                                      VK_COMMAND_BUFFER_LEVEL_PRIMARY, kFramesInFlight};
  check(vkAllocateCommandBuffers(gpu.device, &cmdInfo, f.cmds), "vkAllocateCommandBuffers");
  VkFenceCreateInfo fenceInfo{VK_STRUCTURE_TYPE_FENCE_CREATE_INFO, nullptr, VK_FENCE_CREATE_SIGNALED_BIT};
  for (VkFence& fence : f.fences) check(vkCreateFence(gpu.device, &fenceInfo, nullptr, &fence), "vkCreateFence");
  return f;
}

// Waits for the slot's previous use, then begins its command buffer.
VkCommandBuffer beginSlot(const Gpu& gpu, const Frames& f, uint32_t frame) {
  const VkFence fence = f.fences[frame % kFramesInFlight];
  check(vkWaitForFences(gpu.device, 1, &fence, VK_TRUE, UINT64_MAX), "vkWaitForFences");
  check(vkResetFences(gpu.device, 1, &fence), "vkResetFences");
  VkCommandBufferBeginInfo begin{VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO, nullptr,
                                 VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT};
  check(vkBeginCommandBuffer(f.cmds[frame % kFramesInFlight], &begin), "vkBeginCommandBuffer");
  return f.cmds[frame % kFramesInFlight];
}

void submitSlot(const Gpu& gpu, const Frames& f, uint32_t frame) {
  const VkCommandBuffer cmd = f.cmds[frame % kFramesInFlight];
  check(vkEndCommandBuffer(cmd), "vkEndCommandBuffer");
  VkSubmitInfo submit{VK_STRUCTURE_TYPE_SUBMIT_INFO, nullptr, 0, nullptr, nullptr, 1, &cmd};
  check(vkQueueSubmit(gpu.queue, 1, &submit, f.fences[frame % kFramesInFlight]), "vkQueueSubmit");
}

void destroy(const Gpu& gpu, const Frames& f) {
  for (VkFence fence : f.fences) vkDestroyFence(gpu.device, fence, nullptr);
  vkDestroyCommandPool(gpu.device, f.pool, nullptr);
}

// ---- (5) and (7) What consumes Raybridge's outputs here: a copy of the last frame into host memory.

// An engine writes descriptors where this program records copies; either is set up from outputs() once, and
// again only when outputs().generation moves (the images changed).
struct Readback {
  struct Source {
    VkImage image = VK_NULL_HANDLE;
    VkImageAspectFlags aspect = VK_IMAGE_ASPECT_COLOR_BIT;
    VkImageLayout layout = VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL;
    VkDeviceSize offset = 0;  // in `buffer`
  };
  uint32_t width = 0, height = 0;
  Buffer buffer;  // shadow and AO (half floats), depth (floats), motion (half pairs)
  Source shadow, ao, depth, motion;
  uint64_t generation = 0;  // of the outputs `shadow` and `ao` were taken from
};

Readback createReadback(const Gpu& gpu, const GBuffer& g) {
  const VkDeviceSize pixels = VkDeviceSize(g.width) * g.height;
  Readback r{.width = g.width,
             .height = g.height,
             .buffer = makeBuffer(gpu, pixels * (2 + 2 + 4 + 4), VK_BUFFER_USAGE_TRANSFER_DST_BIT)};
  r.depth = {g.depth.image, g.depth.aspect, VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL, pixels * 4};
  r.motion = {g.motion.image, g.motion.aspect, VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL, pixels * 8};
  return r;
}

void takeOutputs(Readback& r, const rb::HybridOutputs& out) {
  for (const rb::EffectImage* image : {&out.shadow, &out.ao}) {
    if (!image->image || image->width != r.width || image->height != r.height)
      fail("rb::HybridEffects' shadow and AO outputs are not " + std::to_string(r.width) + "x" +
           std::to_string(r.height));
  }
  const VkDeviceSize pixels = VkDeviceSize(r.width) * r.height;
  r.shadow = {out.shadow.image, VK_IMAGE_ASPECT_COLOR_BIT, out.shadow.layout, 0};
  r.ao = {out.ao.image, VK_IMAGE_ASPECT_COLOR_BIT, out.ao.layout, pixels * 2};
  r.generation = out.generation;
}

// After record(): shadow, AO, depth and motion vectors into the buffer, made visible to the host.
void recordReadback(VkCommandBuffer cmd, const Readback& r) {
  for (const Readback::Source& s : {r.shadow, r.ao, r.depth, r.motion}) {
    transition(cmd, s.image, s.aspect, s.layout, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, VK_PIPELINE_STAGE_TRANSFER_BIT,
               VK_ACCESS_TRANSFER_READ_BIT);
    const VkBufferImageCopy region{s.offset, 0, 0, {s.aspect, 0, 0, 1}, {0, 0, 0}, {r.width, r.height, 1}};
    vkCmdCopyImageToBuffer(cmd, s.image, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, r.buffer.buffer, 1, &region);
    transition(cmd, s.image, s.aspect, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, s.layout,
               VK_PIPELINE_STAGE_ALL_COMMANDS_BIT, VK_ACCESS_MEMORY_READ_BIT);
  }
  VkMemoryBarrier toHost{VK_STRUCTURE_TYPE_MEMORY_BARRIER, nullptr, VK_ACCESS_TRANSFER_WRITE_BIT,
                         VK_ACCESS_HOST_READ_BIT};
  vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_PIPELINE_STAGE_HOST_BIT, 0, 1, &toHost, 0, nullptr, 0,
                       nullptr);
}

float halfToFloat(uint16_t h) {
  const int e = (h >> 10) & 31, m = h & 1023;
  const float v = e == 0 ? std::ldexp(float(m), -24) : e == 31 ? INFINITY : std::ldexp(float(m | 1024), e - 25);
  return (h & 0x8000) ? -v : v;
}

void writePfm(const std::filesystem::path& path, uint32_t w, uint32_t h, int channels, const std::vector<float>& px) {
  FILE* f = std::fopen(path.string().c_str(), "wb");
  if (!f) fail("cannot write " + path.string());
  std::fprintf(f, "%s\n%u %u\n-1.0\n", channels == 3 ? "PF" : "Pf", w, h);
  for (uint32_t y = h; y-- > 0;) std::fwrite(&px[size_t(y) * w * channels], sizeof(float), size_t(w) * channels, f);
  std::fclose(f);
}

void writeCamera(const std::filesystem::path& path, uint32_t width, uint32_t height, const Camera& camera) {
  FILE* f = std::fopen(path.string().c_str(), "w");
  if (!f) fail("cannot write camera.txt");
  std::fprintf(f, "width %u\nheight %u\neye %.17g %.17g %.17g\n", width, height, camera.eye[0], camera.eye[1],
               camera.eye[2]);
  for (const auto& [name, m] : {std::pair{"view", camera.view}, std::pair{"projection", camera.projection},
                                std::pair{"previousView", camera.previousView}}) {
    std::fprintf(f, "%s", name);
    for (int i = 0; i < 16; ++i) std::fprintf(f, " %.9g", m[i]);
    std::fprintf(f, "\n");
  }
  std::fclose(f);
}

// The raw images as PFM, a composite PNG (AO and shadow over a grey albedo, blue sky), the camera.
void writeOutputs(const std::filesystem::path& dir, const Readback& r, const Camera& camera) {
  std::error_code error;
  std::filesystem::create_directories(dir, error);
  if (error) fail("cannot create " + dir.string() + ": " + error.message());
  const size_t pixels = size_t(r.width) * r.height;
  const auto* halfs = static_cast<const uint16_t*>(r.buffer.mapped);
  const auto* floats = reinterpret_cast<const float*>(halfs + 2 * pixels);
  const auto* motionHalfs = reinterpret_cast<const uint16_t*>(floats + pixels);
  std::vector<float> shadow(pixels), ao(pixels), depth(floats, floats + pixels), motion(3 * pixels, 0.0f);
  std::vector<uint8_t> png(3 * pixels);
  for (size_t i = 0; i < pixels; ++i) {
    shadow[i] = halfToFloat(halfs[i]);
    ao[i] = halfToFloat(halfs[pixels + i]);
    motion[3 * i] = halfToFloat(motionHalfs[2 * i]);
    motion[3 * i + 1] = halfToFloat(motionHalfs[2 * i + 1]);
    const float lit = 0.85f * ao[i] * (0.3f + 0.7f * shadow[i]), sky[3] = {0.45f, 0.62f, 0.9f};
    for (int c = 0; c < 3; ++c)
      png[3 * i + c] = uint8_t(255.0f * std::clamp(depth[i] == 0.0f ? sky[c] : lit, 0.0f, 1.0f));
  }
  writePfm(dir / "shadow.pfm", r.width, r.height, 1, shadow);
  writePfm(dir / "ao.pfm", r.width, r.height, 1, ao);
  writePfm(dir / "depth.pfm", r.width, r.height, 1, depth);
  writePfm(dir / "motion.pfm", r.width, r.height, 3, motion);
  stbi_write_png((dir / "composite.png").string().c_str(), int(r.width), int(r.height), 3, png.data(),
                 int(r.width) * 3);
  writeCamera(dir / "camera.txt", r.width, r.height, camera);
}

void destroy(const Gpu& gpu) {
  vkDestroyDevice(gpu.device, nullptr);
  if (gpu.messenger) vkDestroyDebugUtilsMessengerEXT(gpu.instance, gpu.messenger, nullptr);
  vkDestroyInstance(gpu.instance, nullptr);
}

}  // namespace

int main(int argc, char** argv) {
  Options opt;
  CLI::App cli{"Raybridge in a bare Vulkan program: G-buffer, hard shadows and AO"};
  cli.add_option("--out", opt.outDir, "output folder");
  cli.add_option("--width", opt.width)->check(CLI::Range(8u, 8192u));
  cli.add_option("--height", opt.height)->check(CLI::Range(8u, 8192u));
  cli.add_option("--frames", opt.frames, "frames to render (the camera moves every frame)")
      ->check(CLI::Range(1u, 1000u));
  cli.add_flag("--validate", opt.validate, "enable the validation layer (also RAYBRIDGE_VALIDATION=1)");
  CLI11_PARSE(cli, argc, argv);
  const char* env = std::getenv("RAYBRIDGE_VALIDATION");
  opt.validate |= env && *env && std::strcmp(env, "0") != 0;

  // (1) Device: a Vulkan 1.3 instance, a device with Raybridge's extensions and features, a graphics queue.
  Gpu gpu;
  createInstance(gpu, opt.validate);
  pickPhysicalDevice(gpu);
  createDevice(gpu);

  // (2) Raybridge adopts the device: the handles, the loader's entry point, the instance's API version.
  std::unique_ptr<rb::Context> ctx = check(rb::Context::create({.instance = gpu.instance,
                                                                .physicalDevice = gpu.physicalDevice,
                                                                .device = gpu.device,
                                                                .getInstanceProcAddr = vkGetInstanceProcAddr,
                                                                .framesInFlight = kFramesInFlight,
                                                                .mainQueueFamily = gpu.queueFamily,
                                                                .apiVersion = kApiVersion}),
                                           "rb::Context::create");

  // (3) Meshes: registered in place; the BLAS builds are queued and recorded by the first record().
  std::unique_ptr<rb::AccelerationStructureService> service = check(rb::AccelerationStructureService::create(*ctx),
                                                                    "rb::AccelerationStructureService::create");
  const Scene scene = createScene(gpu, *service);

  // (4) G-buffer: the program's images and pipeline (described per frame by describeGBuffer).
  const GBuffer gbuffer = createGBuffer(gpu, opt.width, opt.height);

  // (5) Effects: preset Low at the G-buffer's size, so create() allocates the outputs and what reads them can be
  // set up now, once.
  std::unique_ptr<rb::HybridEffects> effects =
      check(rb::HybridEffects::create(*ctx, service.get(),
                                      rb::withPreset({.width = opt.width, .height = opt.height}, rb::Preset::Low)),
            "rb::HybridEffects::create");
  Readback readback = createReadback(gpu, gbuffer);
  takeOutputs(readback, effects->outputs());

  // (6) Frames: two in flight; each rasterises the G-buffer, hands it over and records the effects after it.
  Frames frames = createFrames(gpu);
  Camera camera;
  for (uint32_t frame = 0; frame < opt.frames; ++frame) {
    const VkCommandBuffer cmd = beginSlot(gpu, frames, frame);
    ctx->beginFrame();  // the slot's fence is signalled: its previous use is done
    camera = cameraOfFrame(frame, opt.width, opt.height);
    rasterGBuffer(cmd, gbuffer, scene, camera);
    handOverGBuffer(cmd, gbuffer);
    // The G-buffer contract, the scene's instances and the sun; Raybridge records BLAS builds, TLAS, shadows, AO.
    const rb::HybridFrame inputs{.gbuffer = describeGBuffer(gbuffer, camera),
                                 .instances = scene.instances,
                                 .light = {.direction = {minimal::kToSun[0], minimal::kToSun[1], minimal::kToSun[2]}}};
    check(effects->record(cmd, inputs), "rb::HybridEffects::record");
    // The images changed (a resize, an effect switched): what reads them is set up again.
    if (effects->outputs().generation != readback.generation) takeOutputs(readback, effects->outputs());
    if (frame + 1 == opt.frames) recordReadback(cmd, readback);
    submitSlot(gpu, frames, frame);
  }
  check(vkDeviceWaitIdle(gpu.device), "vkDeviceWaitIdle");

  // (7) Outputs: the last frame's images and the camera it was drawn with.
  writeOutputs(opt.outDir, readback, camera);

  // Shutdown: Raybridge first (the GPU is idle), then the program's own objects.
  effects.reset();
  service.reset();
  ctx.reset();
  destroy(gpu, frames);
  destroy(gpu, readback.buffer);
  destroy(gpu, gbuffer);
  destroy(gpu, scene);
  destroy(gpu);
  std::printf("minimal_integration: %u frames of %ux%u written to %s; %u validation errors%s\n", opt.frames, opt.width,
              opt.height, opt.outDir.c_str(), gpu.validationErrors, opt.validate ? "" : " (validation off)");
  return gpu.validationErrors ? 2 : 0;
}
