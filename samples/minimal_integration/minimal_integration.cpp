// minimal_integration: Raybridge in a bare Vulkan program, independent of the sample engine and of
// rb::HeadlessDevice. It creates its own instance (volk loads Vulkan), device and queue, rasterizes its own
// G-buffer with dynamic rendering — reversed-Z D32 depth with an infinite far plane, octahedral normals
// (rbEncodeOctahedral from shaders/raybridge_gbuffer.glsl) and motion vectors of a moving camera — describes
// it as an rb::GBufferDesc and lets rb::HybridEffects (preset Low: hard shadows, 4-ray AO, denoised) trace
// into its own command buffers, two frames in flight. What it proves: the public headers are enough to
// integrate.
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
#include <string>
#include <vector>

#include "minimal_integration_shaders.h"
#include "minimal_scene.h"

namespace {

constexpr uint32_t kFramesInFlight = 2;
uint32_t gValidationErrors = 0;
VkDevice gDevice = VK_NULL_HANDLE;
VkPhysicalDeviceMemoryProperties gMemory{};

VKAPI_ATTR VkBool32 VKAPI_CALL onMessage(VkDebugUtilsMessageSeverityFlagBitsEXT severity,
                                         VkDebugUtilsMessageTypeFlagsEXT,
                                         const VkDebugUtilsMessengerCallbackDataEXT* data, void*) {
  if (severity & VK_DEBUG_UTILS_MESSAGE_SEVERITY_ERROR_BIT_EXT) {
    ++gValidationErrors;
    std::fprintf(stderr, "[validation] %s\n", data->pMessage);
  }
  return VK_FALSE;
}

[[noreturn]] void fail(const std::string& what) {
  std::fprintf(stderr, "minimal_integration: %s\n", what.c_str());
  std::exit(1);
}
void check(VkResult r, const char* what) {
  if (r != VK_SUCCESS) fail(std::string(what) + " failed with VkResult " + std::to_string(int(r)));
}
void check(const rb::Status& s, const char* what) {
  if (!s.ok()) fail(std::string(what) + ": " + s.error().message);
}
template <typename T>
T check(rb::Result<T> r, const char* what) {
  if (!r.ok()) fail(std::string(what) + ": " + r.error().message);
  return std::move(r).value();
}

uint32_t memoryType(uint32_t typeBits, VkMemoryPropertyFlags want) {
  for (uint32_t i = 0; i < gMemory.memoryTypeCount; ++i) {
    if ((typeBits & (1u << i)) && (gMemory.memoryTypes[i].propertyFlags & want) == want) return i;
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
Buffer makeBuffer(VkDeviceSize size, VkBufferUsageFlags usage, const void* data = nullptr) {
  Buffer b;
  VkBufferCreateInfo info{VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO, nullptr, 0, size, usage};
  check(vkCreateBuffer(gDevice, &info, nullptr, &b.buffer), "vkCreateBuffer");
  VkMemoryRequirements req;
  vkGetBufferMemoryRequirements(gDevice, b.buffer, &req);
  VkMemoryAllocateFlagsInfo flags{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_FLAGS_INFO, nullptr,
                                  VK_MEMORY_ALLOCATE_DEVICE_ADDRESS_BIT};
  const bool addressable = usage & VK_BUFFER_USAGE_SHADER_DEVICE_ADDRESS_BIT;
  VkMemoryAllocateInfo alloc{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO, addressable ? &flags : nullptr, req.size,
                             memoryType(req.memoryTypeBits,
                                        VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT | VK_MEMORY_PROPERTY_HOST_COHERENT_BIT)};
  check(vkAllocateMemory(gDevice, &alloc, nullptr, &b.memory), "vkAllocateMemory");
  check(vkBindBufferMemory(gDevice, b.buffer, b.memory, 0), "vkBindBufferMemory");
  check(vkMapMemory(gDevice, b.memory, 0, VK_WHOLE_SIZE, 0, &b.mapped), "vkMapMemory");
  if (data) std::memcpy(b.mapped, data, size);
  VkBufferDeviceAddressInfo addressInfo{VK_STRUCTURE_TYPE_BUFFER_DEVICE_ADDRESS_INFO, nullptr, b.buffer};
  if (addressable) b.address = vkGetBufferDeviceAddress(gDevice, &addressInfo);
  return b;
}

struct Image {
  VkImage image = VK_NULL_HANDLE;
  VkDeviceMemory memory = VK_NULL_HANDLE;
  VkImageView view = VK_NULL_HANDLE;
  VkImageAspectFlags aspect = 0;
};
Image makeImage(VkPhysicalDevice pd, uint32_t w, uint32_t h, VkFormat format, VkImageUsageFlags usage,
                VkImageAspectFlags aspect) {
  VkFormatProperties props;
  vkGetPhysicalDeviceFormatProperties(pd, format, &props);
  const VkFormatFeatureFlags attachment = aspect == VK_IMAGE_ASPECT_DEPTH_BIT
                                              ? VK_FORMAT_FEATURE_DEPTH_STENCIL_ATTACHMENT_BIT
                                              : VK_FORMAT_FEATURE_COLOR_ATTACHMENT_BIT;
  if ((props.optimalTilingFeatures & attachment) == 0)
    fail("format " + std::to_string(format) + " cannot be rendered to");
  Image img;
  img.aspect = aspect;
  VkImageCreateInfo info{VK_STRUCTURE_TYPE_IMAGE_CREATE_INFO};
  info.imageType = VK_IMAGE_TYPE_2D;
  info.format = format;
  info.extent = {w, h, 1};
  info.mipLevels = info.arrayLayers = 1;
  info.samples = VK_SAMPLE_COUNT_1_BIT;
  info.usage = usage | VK_IMAGE_USAGE_SAMPLED_BIT | VK_IMAGE_USAGE_TRANSFER_SRC_BIT;
  check(vkCreateImage(gDevice, &info, nullptr, &img.image), "vkCreateImage");
  VkMemoryRequirements req;
  vkGetImageMemoryRequirements(gDevice, img.image, &req);
  VkMemoryAllocateInfo alloc{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO, nullptr, req.size,
                             memoryType(req.memoryTypeBits, VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT)};
  check(vkAllocateMemory(gDevice, &alloc, nullptr, &img.memory), "vkAllocateMemory");
  check(vkBindImageMemory(gDevice, img.image, img.memory, 0), "vkBindImageMemory");
  VkImageViewCreateInfo view{VK_STRUCTURE_TYPE_IMAGE_VIEW_CREATE_INFO,
                             nullptr,
                             0,
                             img.image,
                             VK_IMAGE_VIEW_TYPE_2D,
                             format,
                             {},
                             {aspect, 0, 1, 0, 1}};
  check(vkCreateImageView(gDevice, &view, nullptr, &img.view), "vkCreateImageView");
  return img;
}

// Every barrier here waits for all earlier work: the program favours obviously correct over minimal.
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

}  // namespace

int main(int argc, char** argv) {
  std::string outDir = "minimal_out";
  uint32_t width = 640, height = 360, frames = 4;
  bool validate = false;
  CLI::App cli{"Raybridge in a bare Vulkan program: G-buffer, hard shadows and AO"};
  cli.add_option("--out", outDir, "output folder");
  cli.add_option("--width", width)->check(CLI::Range(8u, 8192u));
  cli.add_option("--height", height)->check(CLI::Range(8u, 8192u));
  cli.add_option("--frames", frames, "frames to render (the camera moves every frame)")->check(CLI::Range(1u, 1000u));
  cli.add_flag("--validate", validate, "enable the validation layer (also RAYBRIDGE_VALIDATION=1)");
  CLI11_PARSE(cli, argc, argv);
  const char* env = std::getenv("RAYBRIDGE_VALIDATION");
  validate |= env && *env && std::strcmp(env, "0") != 0;

  // Instance, with validation and synchronization validation when asked for.
  check(volkInitialize(), "volkInitialize (is the Vulkan loader installed?)");
  VkApplicationInfo app{
      VK_STRUCTURE_TYPE_APPLICATION_INFO, nullptr, "minimal_integration", 1, nullptr, 0, VK_API_VERSION_1_3};
  VkDebugUtilsMessengerCreateInfoEXT messengerInfo{VK_STRUCTURE_TYPE_DEBUG_UTILS_MESSENGER_CREATE_INFO_EXT};
  messengerInfo.messageSeverity = VK_DEBUG_UTILS_MESSAGE_SEVERITY_ERROR_BIT_EXT;
  messengerInfo.messageType = VK_DEBUG_UTILS_MESSAGE_TYPE_GENERAL_BIT_EXT |
                              VK_DEBUG_UTILS_MESSAGE_TYPE_VALIDATION_BIT_EXT;
  messengerInfo.pfnUserCallback = &onMessage;
  const VkValidationFeatureEnableEXT syncValidation = VK_VALIDATION_FEATURE_ENABLE_SYNCHRONIZATION_VALIDATION_EXT;
  VkValidationFeaturesEXT features{VK_STRUCTURE_TYPE_VALIDATION_FEATURES_EXT, &messengerInfo, 1, &syncValidation};
  const char* layer = "VK_LAYER_KHRONOS_validation";
  const char* debugUtils = VK_EXT_DEBUG_UTILS_EXTENSION_NAME;
  VkInstanceCreateInfo ici{VK_STRUCTURE_TYPE_INSTANCE_CREATE_INFO,
                           validate ? &features : nullptr,
                           0,
                           &app,
                           validate ? 1u : 0u,
                           &layer,
                           validate ? 1u : 0u,
                           &debugUtils};
  VkInstance instance;
  check(vkCreateInstance(&ici, nullptr, &instance),
        validate ? "vkCreateInstance with VK_LAYER_KHRONOS_validation" : "vkCreateInstance");
  volkLoadInstanceOnly(instance);
  VkDebugUtilsMessengerEXT messenger = VK_NULL_HANDLE;
  if (validate) check(vkCreateDebugUtilsMessengerEXT(instance, &messengerInfo, nullptr, &messenger), "messenger");

  // The first device with Raybridge's extensions and a graphics queue.
  uint32_t count = 0;
  vkEnumeratePhysicalDevices(instance, &count, nullptr);
  std::vector<VkPhysicalDevice> devices(count);
  vkEnumeratePhysicalDevices(instance, &count, devices.data());
  VkPhysicalDevice pd = VK_NULL_HANDLE;
  uint32_t family = 0;
  for (VkPhysicalDevice candidate : devices) {
    vkEnumerateDeviceExtensionProperties(candidate, nullptr, &count, nullptr);
    std::vector<VkExtensionProperties> exts(count);
    vkEnumerateDeviceExtensionProperties(candidate, nullptr, &count, exts.data());
    bool all = true;
    for (const char* name : rb::requiredDeviceExtensions()) {
      all &= std::any_of(exts.begin(), exts.end(), [&](auto& e) { return std::strcmp(e.extensionName, name) == 0; });
    }
    vkGetPhysicalDeviceQueueFamilyProperties(candidate, &count, nullptr);
    std::vector<VkQueueFamilyProperties> families(count);
    vkGetPhysicalDeviceQueueFamilyProperties(candidate, &count, families.data());
    for (uint32_t i = 0; all && !pd && i < count; ++i) {
      if (families[i].queueFlags & VK_QUEUE_GRAPHICS_BIT) pd = candidate, family = i;
    }
  }
  if (!pd) fail("no Vulkan device supports ray tracing pipelines (lavapipe needs Mesa 25)");
  vkGetPhysicalDeviceMemoryProperties(pd, &gMemory);

  rb::RequiredFeatures required;  // Raybridge's features, chained ahead of the program's own
  VkPhysicalDeviceVulkan13Features v13{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_3_FEATURES};
  v13.dynamicRendering = VK_TRUE;
  const float priority = 1.0f;
  VkDeviceQueueCreateInfo qci{VK_STRUCTURE_TYPE_DEVICE_QUEUE_CREATE_INFO, nullptr, 0, family, 1, &priority};
  auto extensions = rb::requiredDeviceExtensions();
  VkDeviceCreateInfo dci{VK_STRUCTURE_TYPE_DEVICE_CREATE_INFO, required.link(&v13), 0, 1, &qci, 0, nullptr,
                         uint32_t(extensions.size()),          extensions.data()};
  check(vkCreateDevice(pd, &dci, nullptr, &gDevice), "vkCreateDevice");
  volkLoadDevice(gDevice);
  VkQueue queue;
  vkGetDeviceQueue(gDevice, family, 0, &queue);

  // Raybridge adopts the device; the acceleration-structure service and the effects front end come from it.
  auto ctx =
      check(rb::Context::create({instance, pd, gDevice, vkGetInstanceProcAddr, kFramesInFlight, nullptr, family}),
            "rb::Context::create");
  auto service = check(rb::AccelerationStructureService::create(*ctx), "rb::AccelerationStructureService::create");
  auto effects = check(rb::HybridEffects::create(*ctx, service.get(), rb::withPreset({}, rb::Preset::Low)),
                       "rb::HybridEffects::create");

  // The scene in the program's own device-address buffers, registered in place (no copy, no upload).
  const std::vector<minimal::Mesh> scene = minimal::makeScene();
  std::vector<Buffer> vertexBuffers, indexBuffers;
  std::vector<rb::Instance> instances;
  const VkBufferUsageFlags geometry = VK_BUFFER_USAGE_SHADER_DEVICE_ADDRESS_BIT |
                                      VK_BUFFER_USAGE_ACCELERATION_STRUCTURE_BUILD_INPUT_READ_ONLY_BIT_KHR;
  for (const minimal::Mesh& m : scene) {
    const VkDeviceSize vBytes = m.positions.size() * sizeof(float), iBytes = m.indices.size() * sizeof(uint32_t);
    vertexBuffers.push_back(makeBuffer(vBytes, geometry | VK_BUFFER_USAGE_VERTEX_BUFFER_BIT, m.positions.data()));
    indexBuffers.push_back(makeBuffer(iBytes, geometry | VK_BUFFER_USAGE_INDEX_BUFFER_BIT, m.indices.data()));
    rb::MeshDesc desc;
    desc.vertexAddress = vertexBuffers.back().address;
    desc.vertexBufferBytes = vBytes;
    desc.vertexCount = uint32_t(m.positions.size() / 3);
    desc.indexAddress = indexBuffers.back().address;
    desc.indexBufferBytes = iBytes;
    desc.triangleCount = uint32_t(m.indices.size() / 3);
    desc.hostVertices = m.positions.data();
    desc.hostIndices = m.indices.data();
    desc.debugName = m.name;
    rb::Instance instance;  // identity transform: the meshes are in world space
    instance.mesh = check(service->registerMesh(desc), "registerMesh");
    instances.push_back(instance);
  }

  // G-buffer: reversed-Z depth, octahedral normals, motion vectors; one set, reused every frame.
  const VkFormat depthFormat = VK_FORMAT_D32_SFLOAT, normalFormat = VK_FORMAT_R16G16_SNORM,
                 motionFormat = VK_FORMAT_R16G16_SFLOAT;
  Image depth = makeImage(pd, width, height, depthFormat, VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT,
                          VK_IMAGE_ASPECT_DEPTH_BIT);
  Image normal = makeImage(pd, width, height, normalFormat, VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT,
                           VK_IMAGE_ASPECT_COLOR_BIT);
  Image motion = makeImage(pd, width, height, motionFormat, VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT,
                           VK_IMAGE_ASPECT_COLOR_BIT);

  // The G-buffer pipeline (dynamic rendering, depth test GREATER against a clear of 0).
  VkShaderModule modules[2];
  const std::pair<const uint32_t*, size_t> code[2] = {
      {minimal::spirv::gbuffer_vert, sizeof minimal::spirv::gbuffer_vert},
      {minimal::spirv::gbuffer_frag, sizeof minimal::spirv::gbuffer_frag}};
  for (int i = 0; i < 2; ++i) {
    VkShaderModuleCreateInfo info{VK_STRUCTURE_TYPE_SHADER_MODULE_CREATE_INFO, nullptr, 0, code[i].second,
                                  code[i].first};
    check(vkCreateShaderModule(gDevice, &info, nullptr, &modules[i]), "vkCreateShaderModule");
  }
  VkPushConstantRange pushRange{VK_SHADER_STAGE_VERTEX_BIT, 0, 2 * 16 * sizeof(float)};
  VkPipelineLayoutCreateInfo layoutInfo{
      VK_STRUCTURE_TYPE_PIPELINE_LAYOUT_CREATE_INFO, nullptr, 0, 0, nullptr, 1, &pushRange};
  VkPipelineLayout layout;
  check(vkCreatePipelineLayout(gDevice, &layoutInfo, nullptr, &layout), "vkCreatePipelineLayout");
  VkPipelineShaderStageCreateInfo stages[2] = {{VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO, nullptr, 0,
                                                VK_SHADER_STAGE_VERTEX_BIT, modules[0], "main"},
                                               {VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO, nullptr, 0,
                                                VK_SHADER_STAGE_FRAGMENT_BIT, modules[1], "main"}};
  VkVertexInputBindingDescription binding{0, 3 * sizeof(float), VK_VERTEX_INPUT_RATE_VERTEX};
  VkVertexInputAttributeDescription attribute{0, 0, VK_FORMAT_R32G32B32_SFLOAT, 0};
  VkPipelineVertexInputStateCreateInfo vertexInput{
      VK_STRUCTURE_TYPE_PIPELINE_VERTEX_INPUT_STATE_CREATE_INFO, nullptr, 0, 1, &binding, 1, &attribute};
  VkPipelineInputAssemblyStateCreateInfo assembly{VK_STRUCTURE_TYPE_PIPELINE_INPUT_ASSEMBLY_STATE_CREATE_INFO, nullptr,
                                                  0, VK_PRIMITIVE_TOPOLOGY_TRIANGLE_LIST};
  VkViewport viewport{0, 0, float(width), float(height), 0, 1};
  VkRect2D scissor{{0, 0}, {width, height}};
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
  const VkFormat colorFormats[2] = {normalFormat, motionFormat};
  VkPipelineRenderingCreateInfo rendering{
      VK_STRUCTURE_TYPE_PIPELINE_RENDERING_CREATE_INFO, nullptr, 0, 2, colorFormats, depthFormat};
  VkGraphicsPipelineCreateInfo pipelineInfo{.sType = VK_STRUCTURE_TYPE_GRAPHICS_PIPELINE_CREATE_INFO,
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
                                            .layout = layout};
  VkPipeline pipeline;
  check(vkCreateGraphicsPipelines(gDevice, VK_NULL_HANDLE, 1, &pipelineInfo, nullptr, &pipeline), "G-buffer pipeline");

  // Frame slots: a command buffer and a fence each.
  VkCommandPoolCreateInfo poolInfo{VK_STRUCTURE_TYPE_COMMAND_POOL_CREATE_INFO, nullptr,
                                   VK_COMMAND_POOL_CREATE_RESET_COMMAND_BUFFER_BIT, family};
  VkCommandPool pool;
  check(vkCreateCommandPool(gDevice, &poolInfo, nullptr, &pool), "vkCreateCommandPool");
  VkCommandBuffer cmds[kFramesInFlight];
  VkCommandBufferAllocateInfo cmdInfo{VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO, nullptr, pool,
                                      VK_COMMAND_BUFFER_LEVEL_PRIMARY, kFramesInFlight};
  check(vkAllocateCommandBuffers(gDevice, &cmdInfo, cmds), "vkAllocateCommandBuffers");
  VkFence fences[kFramesInFlight];
  for (VkFence& f : fences) {
    VkFenceCreateInfo info{VK_STRUCTURE_TYPE_FENCE_CREATE_INFO, nullptr, VK_FENCE_CREATE_SIGNALED_BIT};
    check(vkCreateFence(gDevice, &info, nullptr, &f), "vkCreateFence");
  }
  const size_t pixels = size_t(width) * height;
  Buffer readback = makeBuffer(pixels * (2 + 2 + 4 + 4),
                               VK_BUFFER_USAGE_TRANSFER_DST_BIT);  // shadow, ao, depth, motion

  const VkPipelineStageFlags passReaders = VK_PIPELINE_STAGE_RAY_TRACING_SHADER_BIT_KHR |
                                           VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT;
  float view[16], projection[16], previousView[16];
  double eye[3], target[3];
  minimal::reversedInfiniteProjection(minimal::kFovYDegrees, float(width) / float(height), minimal::kNearPlane,
                                      projection);
  for (uint32_t frame = 0; frame < frames; ++frame) {
    VkCommandBuffer cmd = cmds[frame % kFramesInFlight];
    VkFence fence = fences[frame % kFramesInFlight];
    check(vkWaitForFences(gDevice, 1, &fence, VK_TRUE, UINT64_MAX), "vkWaitForFences");
    check(vkResetFences(gDevice, 1, &fence), "vkResetFences");
    ctx->beginFrame();  // the slot's fence is signalled: its previous use is done
    VkCommandBufferBeginInfo begin{VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO, nullptr,
                                   VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT};
    check(vkBeginCommandBuffer(cmd, &begin), "vkBeginCommandBuffer");

    // Cameras: the previous frame's (for the motion vectors) and this frame's.
    minimal::cameraAt(frame ? frame - 1 : 0, eye, target);
    minimal::viewMatrix(eye, target, previousView);
    minimal::cameraAt(frame, eye, target);
    minimal::viewMatrix(eye, target, view);
    const float toPixels[16] = {width * 0.5f,  0, 0, 0, 0, height * 0.5f, 0, 0, 0, 0, 1, 0, width * 0.5f,
                                height * 0.5f, 0, 1};
    float constants[32], previousClip[16];
    minimal::multiply(projection, view, constants);
    minimal::multiply(projection, previousView, previousClip);
    minimal::multiply(toPixels, previousClip, constants + 16);

    // The G-buffer pass; the previous frame's passes have read the images, their contents are discarded.
    transition(cmd, depth.image, depth.aspect, VK_IMAGE_LAYOUT_UNDEFINED, VK_IMAGE_LAYOUT_DEPTH_ATTACHMENT_OPTIMAL,
               VK_PIPELINE_STAGE_EARLY_FRAGMENT_TESTS_BIT | VK_PIPELINE_STAGE_LATE_FRAGMENT_TESTS_BIT,
               VK_ACCESS_DEPTH_STENCIL_ATTACHMENT_READ_BIT | VK_ACCESS_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT);
    for (const Image* img : {&normal, &motion}) {
      transition(cmd, img->image, img->aspect, VK_IMAGE_LAYOUT_UNDEFINED, VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL,
                 VK_PIPELINE_STAGE_COLOR_ATTACHMENT_OUTPUT_BIT, VK_ACCESS_COLOR_ATTACHMENT_WRITE_BIT);
    }
    VkRenderingAttachmentInfo colors[2] = {{VK_STRUCTURE_TYPE_RENDERING_ATTACHMENT_INFO},
                                           {VK_STRUCTURE_TYPE_RENDERING_ATTACHMENT_INFO}};
    colors[0].imageView = normal.view;
    colors[1].imageView = motion.view;
    for (VkRenderingAttachmentInfo& c : colors) {
      c.imageLayout = VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL;
      c.loadOp = VK_ATTACHMENT_LOAD_OP_CLEAR;
      c.storeOp = VK_ATTACHMENT_STORE_OP_STORE;
    }
    VkRenderingAttachmentInfo depthAttachment = colors[0];
    depthAttachment.imageView = depth.view;
    depthAttachment.imageLayout = VK_IMAGE_LAYOUT_DEPTH_ATTACHMENT_OPTIMAL;
    depthAttachment.clearValue.depthStencil = {0.0f, 0};  // reversed-Z: far (infinity) is 0
    VkRenderingInfo renderingInfo{
        VK_STRUCTURE_TYPE_RENDERING_INFO, nullptr, 0, scissor, 1, 0, 2, colors, &depthAttachment};
    vkCmdBeginRendering(cmd, &renderingInfo);
    vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, pipeline);
    vkCmdPushConstants(cmd, layout, VK_SHADER_STAGE_VERTEX_BIT, 0, sizeof constants, constants);
    for (size_t i = 0; i < scene.size(); ++i) {
      const VkDeviceSize zero = 0;
      vkCmdBindVertexBuffers(cmd, 0, 1, &vertexBuffers[i].buffer, &zero);
      vkCmdBindIndexBuffer(cmd, indexBuffers[i].buffer, 0, VK_INDEX_TYPE_UINT32);
      vkCmdDrawIndexed(cmd, uint32_t(scene[i].indices.size()), 1, 0, 0, 0);
    }
    vkCmdEndRendering(cmd);
    for (const Image* img : {&depth, &normal, &motion}) {
      transition(cmd, img->image, img->aspect,
                 img == &depth ? VK_IMAGE_LAYOUT_DEPTH_ATTACHMENT_OPTIMAL : VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL,
                 VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL, passReaders, VK_ACCESS_SHADER_READ_BIT);
    }

    // Raybridge: the G-buffer contract, the scene's instances and the sun; BLAS builds, TLAS, shadows, AO.
    rb::HybridFrame inputs;
    inputs.gbuffer.width = width;
    inputs.gbuffer.height = height;
    inputs.gbuffer.depth = {depth.view, VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL};
    inputs.gbuffer.depthConvention = rb::DepthConvention::ReversedZ;
    inputs.gbuffer.depthFormat = depthFormat;
    inputs.gbuffer.normal = {normal.view, VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL};
    inputs.gbuffer.normalEncoding = rb::NormalEncoding::Octahedral;
    inputs.gbuffer.motionVectors = {motion.view, VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL};
    std::memcpy(inputs.gbuffer.view, view, sizeof view);
    std::memcpy(inputs.gbuffer.projection, projection, sizeof projection);
    std::memcpy(inputs.gbuffer.cameraPosition, eye, sizeof eye);
    inputs.instances = instances;
    std::memcpy(inputs.light.direction, minimal::kToSun, sizeof minimal::kToSun);
    check(effects->record(cmd, inputs), "rb::HybridEffects::record");

    if (frame + 1 == frames) {  // read the last frame back: shadow, AO, depth, motion vectors
      const rb::HybridOutputs& out = effects->outputs();
      const struct {
        VkImage image;
        VkImageAspectFlags aspect;
        VkImageLayout layout;
        VkDeviceSize offset;
      } reads[4] = {{out.shadow.image, VK_IMAGE_ASPECT_COLOR_BIT, out.shadow.layout, 0},
                    {out.ao.image, VK_IMAGE_ASPECT_COLOR_BIT, out.ao.layout, pixels * 2},
                    {depth.image, depth.aspect, VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL, pixels * 4},
                    {motion.image, motion.aspect, VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL, pixels * 8}};
      for (const auto& r : reads) {
        if (!r.image) fail("rb::HybridEffects produced no shadow or AO image");
        transition(cmd, r.image, r.aspect, r.layout, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL,
                   VK_PIPELINE_STAGE_TRANSFER_BIT, VK_ACCESS_TRANSFER_READ_BIT);
        VkBufferImageCopy region{r.offset, 0, 0, {r.aspect, 0, 0, 1}, {0, 0, 0}, {width, height, 1}};
        vkCmdCopyImageToBuffer(cmd, r.image, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, readback.buffer, 1, &region);
        transition(cmd, r.image, r.aspect, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, r.layout,
                   VK_PIPELINE_STAGE_ALL_COMMANDS_BIT, VK_ACCESS_MEMORY_READ_BIT);
      }
      VkMemoryBarrier toHost{VK_STRUCTURE_TYPE_MEMORY_BARRIER, nullptr, VK_ACCESS_TRANSFER_WRITE_BIT,
                             VK_ACCESS_HOST_READ_BIT};
      vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_PIPELINE_STAGE_HOST_BIT, 0, 1, &toHost, 0, nullptr,
                           0, nullptr);
    }
    check(vkEndCommandBuffer(cmd), "vkEndCommandBuffer");
    VkSubmitInfo submit{VK_STRUCTURE_TYPE_SUBMIT_INFO, nullptr, 0, nullptr, nullptr, 1, &cmd};
    check(vkQueueSubmit(queue, 1, &submit, fence), "vkQueueSubmit");
  }
  check(vkDeviceWaitIdle(gDevice), "vkDeviceWaitIdle");

  // Files: the raw images as PFM, a composite PNG, the camera the last frame was drawn with.
  std::filesystem::create_directories(outDir);
  const auto* halfs = static_cast<const uint16_t*>(readback.mapped);
  const auto* floats = reinterpret_cast<const float*>(halfs + 2 * pixels);
  std::vector<float> shadowPx(pixels), aoPx(pixels), depthPx(floats, floats + pixels), motionPx(3 * pixels, 0.0f);
  std::vector<uint8_t> png(3 * pixels);
  const auto* motionHalfs = reinterpret_cast<const uint16_t*>(floats + pixels);
  for (size_t i = 0; i < pixels; ++i) {
    shadowPx[i] = halfToFloat(halfs[i]);
    aoPx[i] = halfToFloat(halfs[pixels + i]);
    motionPx[3 * i] = halfToFloat(motionHalfs[2 * i]);
    motionPx[3 * i + 1] = halfToFloat(motionHalfs[2 * i + 1]);
    const float lit = 0.85f * aoPx[i] * (0.3f + 0.7f * shadowPx[i]), sky[3] = {0.45f, 0.62f, 0.9f};
    for (int c = 0; c < 3; ++c)
      png[3 * i + c] = uint8_t(255.0f * std::clamp(depthPx[i] == 0.0f ? sky[c] : lit, 0.0f, 1.0f));
  }
  const std::filesystem::path dir(outDir);
  writePfm(dir / "shadow.pfm", width, height, 1, shadowPx);
  writePfm(dir / "ao.pfm", width, height, 1, aoPx);
  writePfm(dir / "depth.pfm", width, height, 1, depthPx);
  writePfm(dir / "motion.pfm", width, height, 3, motionPx);
  stbi_write_png((dir / "composite.png").string().c_str(), int(width), int(height), 3, png.data(), int(width) * 3);
  FILE* cam = std::fopen((dir / "camera.txt").string().c_str(), "w");
  if (!cam) fail("cannot write camera.txt");
  std::fprintf(cam, "width %u\nheight %u\neye %.17g %.17g %.17g\n", width, height, eye[0], eye[1], eye[2]);
  for (const auto& [name, m] :
       {std::pair{"view", view}, std::pair{"projection", projection}, std::pair{"previousView", previousView}}) {
    std::fprintf(cam, "%s", name);
    for (int i = 0; i < 16; ++i) std::fprintf(cam, " %.9g", m[i]);
    std::fprintf(cam, "\n");
  }
  std::fclose(cam);

  // Shutdown: Raybridge first (the GPU is idle), then the program's own objects.
  effects.reset();
  service.reset();
  ctx.reset();
  vkDestroyPipeline(gDevice, pipeline, nullptr);
  vkDestroyPipelineLayout(gDevice, layout, nullptr);
  for (VkShaderModule m : modules) vkDestroyShaderModule(gDevice, m, nullptr);
  for (VkFence f : fences) vkDestroyFence(gDevice, f, nullptr);
  vkDestroyCommandPool(gDevice, pool, nullptr);
  for (const Image* img : {&depth, &normal, &motion}) {
    vkDestroyImageView(gDevice, img->view, nullptr);
    vkDestroyImage(gDevice, img->image, nullptr);
    vkFreeMemory(gDevice, img->memory, nullptr);
  }
  auto destroy = [](const Buffer& b) {
    vkDestroyBuffer(gDevice, b.buffer, nullptr), vkFreeMemory(gDevice, b.memory, nullptr);
  };
  std::for_each(vertexBuffers.begin(), vertexBuffers.end(), destroy);
  std::for_each(indexBuffers.begin(), indexBuffers.end(), destroy);
  destroy(readback);
  vkDestroyDevice(gDevice, nullptr);
  if (messenger) vkDestroyDebugUtilsMessengerEXT(instance, messenger, nullptr);
  vkDestroyInstance(instance, nullptr);
  std::printf("minimal_integration: %u frames of %ux%u written to %s; %u validation errors%s\n", frames, width, height,
              outDir.c_str(), gValidationErrors, validate ? "" : " (validation off)");
  return gValidationErrors ? 2 : 0;
}
