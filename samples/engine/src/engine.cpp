// Engine setup, scene management, render targets, timings and readback.
#include <algorithm>
#include <cstring>

#include "engine_impl.h"
#include "vk_check.h"

namespace sample_engine {

using namespace detail;

// ---------------------------------------------------------------------------------------------------------
// Setup and teardown

std::string Engine::Impl::init(const EngineConfig& config) {
  if (std::string e = ctx.create(config); !e.empty()) return e;
  gpu.init(ctx.physicalDevice, ctx.device, ctx.queue, ctx.queueFamily);
  if (std::string e = pipelines.create(ctx.device); !e.empty()) return e;
  if (std::string e = deformer.create(gpu, ctx); !e.empty()) return e;
  if (std::string e = defaults.create(gpu); !e.empty()) return e;
  if (std::string e = probe.create(gpu, ctx, pipelines); !e.empty()) return e;

  // Per frame: frame uniforms, lighting inputs, tonemap input and the three effect passes' inputs (SSAO, its
  // blur: one sampled and storage set each; shadow visibility).
  constexpr uint32_t kSetsPerFrame = 6;
  // The lighting set also holds the KHR light buffer (storage) and the local shadow views (uniform).
  constexpr uint32_t kSamplersPerFrame = kLightingSetSamplers + 1 + kScreenSetBindings + 2 * kSsaoSetSamplers;
  const VkDevice dev = ctx.device;
  VkDescriptorPoolSize sizes[4] = {{VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER, 2 * kFramesInFlight},
                                   {VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, kSamplersPerFrame * kFramesInFlight},
                                   {VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, kFramesInFlight},
                                   {VK_DESCRIPTOR_TYPE_STORAGE_IMAGE, 2 * kFramesInFlight}};
  VkDescriptorPoolCreateInfo pci{VK_STRUCTURE_TYPE_DESCRIPTOR_POOL_CREATE_INFO};
  pci.maxSets = kSetsPerFrame * kFramesInFlight;
  pci.poolSizeCount = 4;
  pci.pPoolSizes = sizes;
  SE_VK_TRY(vkCreateDescriptorPool(dev, &pci, nullptr, &framePool));

  for (FrameResources& f : frames) {
    VkCommandPoolCreateInfo cpi{VK_STRUCTURE_TYPE_COMMAND_POOL_CREATE_INFO};
    cpi.flags = VK_COMMAND_POOL_CREATE_RESET_COMMAND_BUFFER_BIT;
    cpi.queueFamilyIndex = ctx.queueFamily;
    SE_VK_TRY(vkCreateCommandPool(dev, &cpi, nullptr, &f.pool));
    VkCommandBufferAllocateInfo cai{VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO};
    cai.commandPool = f.pool;
    cai.level = VK_COMMAND_BUFFER_LEVEL_PRIMARY;
    cai.commandBufferCount = 1;
    SE_VK_TRY(vkAllocateCommandBuffers(dev, &cai, &f.cmd));
    VkFenceCreateInfo fci{VK_STRUCTURE_TYPE_FENCE_CREATE_INFO};
    fci.flags = VK_FENCE_CREATE_SIGNALED_BIT;
    SE_VK_TRY(vkCreateFence(dev, &fci, nullptr, &f.fence));
    VkSemaphoreCreateInfo sci{VK_STRUCTURE_TYPE_SEMAPHORE_CREATE_INFO};
    SE_VK_TRY(vkCreateSemaphore(dev, &sci, nullptr, &f.imageAcquired));
    if (std::string e = gpu.createBuffer(sizeof(FrameUniforms), VK_BUFFER_USAGE_UNIFORM_BUFFER_BIT,
                                         VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT | VK_MEMORY_PROPERTY_HOST_COHERENT_BIT,
                                         f.uniforms);
        !e.empty())
      return e;
    VkDescriptorSetLayout layouts[kSetsPerFrame] = {pipelines.frameSetLayout,   pipelines.lightingSetLayout,
                                                    pipelines.tonemapSetLayout, pipelines.ssaoSetLayout,
                                                    pipelines.ssaoSetLayout,    pipelines.screenSetLayout};
    VkDescriptorSet sets[kSetsPerFrame];
    VkDescriptorSetAllocateInfo dai{VK_STRUCTURE_TYPE_DESCRIPTOR_SET_ALLOCATE_INFO};
    dai.descriptorPool = framePool;
    dai.descriptorSetCount = kSetsPerFrame;
    dai.pSetLayouts = layouts;
    SE_VK_TRY(vkAllocateDescriptorSets(dev, &dai, sets));
    f.frameSet = sets[0];
    f.lightingSet = sets[1];
    f.tonemapSet = sets[2];
    f.ssaoSet = sets[3];
    f.ssaoBlurSet = sets[4];
    f.shadowVisibilitySet = sets[5];
    VkDescriptorBufferInfo bi{f.uniforms.buffer, 0, sizeof(FrameUniforms)};
    VkWriteDescriptorSet w{VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET};
    w.dstSet = f.frameSet;
    w.descriptorCount = 1;
    w.descriptorType = VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER;
    w.pBufferInfo = &bi;
    vkUpdateDescriptorSets(dev, 1, &w, 0, nullptr);
    if (ctx.timestampsSupported) {
      VkQueryPoolCreateInfo qci{VK_STRUCTURE_TYPE_QUERY_POOL_CREATE_INFO};
      qci.queryType = VK_QUERY_TYPE_TIMESTAMP;
      qci.queryCount = kTsCount;
      SE_VK_TRY(vkCreateQueryPool(dev, &qci, nullptr, &f.timestamps));
    }
  }
  return createLocalLights();
}

Engine::Impl::~Impl() {
  if (ctx.device) {
    vkDeviceWaitIdle(ctx.device);
    destroySwapchain(true);
    destroyTargets();
    destroyOverlay();
    gpu.destroy(targets.shadowMap);
    destroyLocalLights();
    if (sceneLoaded) destroyScene(gpu, scene);
    deformer.destroy();
    for (FrameResources& f : frames) {
      if (f.timestamps) vkDestroyQueryPool(ctx.device, f.timestamps, nullptr);
      gpu.destroy(f.uniforms);
      gpu.destroy(f.previousModels);
      if (f.imageAcquired) vkDestroySemaphore(ctx.device, f.imageAcquired, nullptr);
      if (f.fence) vkDestroyFence(ctx.device, f.fence, nullptr);
      if (f.pool) vkDestroyCommandPool(ctx.device, f.pool, nullptr);
    }
    if (framePool) vkDestroyDescriptorPool(ctx.device, framePool, nullptr);
    probe.destroy(gpu);
    defaults.destroy(gpu);
    pipelines.destroy(ctx.device);
    gpu.shutdown();
  }
  ctx.destroy();
}

Result<std::unique_ptr<Engine>> Engine::create(const EngineConfig& config) {
  try {
    auto impl = std::make_unique<Impl>();
    if (std::string e = impl->init(config); !e.empty()) return Result<std::unique_ptr<Engine>>::failure(e);
    return Result<std::unique_ptr<Engine>>::success(std::unique_ptr<Engine>(new Engine(std::move(impl))));
  } catch (const std::exception& e) {
    return Result<std::unique_ptr<Engine>>::failure(std::string("engine creation failed: ") + e.what());
  }
}

Engine::Engine(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
Engine::~Engine() = default;

// ---------------------------------------------------------------------------------------------------------
// Accessors

VkInstance Engine::instance() const { return impl_->ctx.instance; }
VkPhysicalDevice Engine::physicalDevice() const { return impl_->ctx.physicalDevice; }
VkDevice Engine::device() const { return impl_->ctx.device; }
VkQueue Engine::queue() const { return impl_->ctx.queue; }
uint32_t Engine::queueFamily() const { return impl_->ctx.queueFamily; }
VkQueue Engine::asyncComputeQueue() const { return impl_->ctx.asyncComputeQueue; }
uint32_t Engine::asyncComputeQueueFamily() const { return impl_->ctx.asyncComputeFamily; }
std::span<const DeformedInstance> Engine::deformedInstances() const { return impl_->deformer.instances(); }
std::span<const glm::mat4> Engine::instanceTransforms() const {
  return impl_->sceneLoaded ? impl_->pose.instanceTransforms() : std::span<const glm::mat4>();
}
PFN_vkGetInstanceProcAddr Engine::getInstanceProcAddr() const { return &vkGetInstanceProcAddr; }
uint32_t Engine::apiVersion() const { return VK_API_VERSION_1_3; }
const DeviceInfo& Engine::deviceInfo() const { return impl_->ctx.info; }
const std::vector<std::string>& Engine::enabledDeviceExtensions() const { return impl_->ctx.deviceExtensions; }
uint32_t Engine::validationErrorCount() const { return impl_->ctx.counters->errors.load(); }
uint32_t Engine::validationWarningCount() const { return impl_->ctx.counters->warnings.load(); }
const Scene& Engine::scene() const { return impl_->scene.cpu; }
std::span<const GpuMesh> Engine::meshes() const { return impl_->scene.meshes; }
std::span<const GpuTexture> Engine::textures() const { return impl_->scene.textureViews; }
Bounds Engine::sceneBounds() const { return impl_->scene.bounds; }
VkExtent2D Engine::renderSize() const { return impl_->targets.extent; }
void Engine::setPrepassHook(PrepassHook hook) { impl_->hook = std::move(hook); }
PassTimings Engine::lastTimings() const { return impl_->timings; }
ShadowMapStats Engine::lastShadowMapStats() const { return impl_->shadowStats; }
uint64_t Engine::frameNumber() const { return impl_->frameCounter; }
std::span<const FrameLight> Engine::frameLights() const { return impl_->frameLights; }
LocalShadowStats Engine::lastLocalShadowStats() const { return impl_->localShadowStats; }

// ---------------------------------------------------------------------------------------------------------
// Scene

Status Engine::loadScene(const Scene& scene) {
  try {
    vkDeviceWaitIdle(impl_->ctx.device);
    ++impl_->sceneVersion;
    impl_->deformer.unload();
    if (impl_->sceneLoaded) destroyScene(impl_->gpu, impl_->scene);
    impl_->sceneLoaded = true;  // partially uploaded resources are destroyed like a full scene
    impl_->frameLights.clear();
    impl_->previousTransforms.clear();  // the first frame of a new scene has no motion
    impl_->hasPreviousCamera = false;
    std::string e = checkLights(scene).error;
    if (e.empty())
      e = uploadScene(impl_->gpu, impl_->ctx, impl_->pipelines, impl_->defaults, scene, impl_->pose, impl_->scene);
    // The rest pose until the first frame; the deformed buffers start as the bind pose.
    if (e.empty()) e = impl_->pose.evaluate(impl_->scene.cpu, 0.0, {}, true).error;
    if (e.empty()) e = impl_->deformer.load(impl_->scene, impl_->pose);
    if (e.empty()) placeLights(impl_->scene.cpu, impl_->pose.nodeWorld(), impl_->frameLights);
    if (!e.empty()) {
      impl_->deformer.unload();
      destroyScene(impl_->gpu, impl_->scene);
      impl_->sceneLoaded = false;
      impl_->frameLights.clear();
      return Status::failure("loadScene: " + e);
    }
    return Status::success();
  } catch (const std::exception& e) {
    return Status::failure(std::string("scene upload failed: ") + e.what());
  }
}

// ---------------------------------------------------------------------------------------------------------
// Render targets

std::string Engine::Impl::createTargets(VkExtent2D extent) {
  destroyTargets();
  targets.extent = extent;
  const VkImageUsageFlags readable = VK_IMAGE_USAGE_SAMPLED_BIT | VK_IMAGE_USAGE_TRANSFER_SRC_BIT;
  std::string e = gpu.createImage({kDepthFormat, extent, VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT | readable,
                                   VK_IMAGE_ASPECT_DEPTH_BIT},
                                  targets.depth);
  if (e.empty())
    e = gpu.createImage({kNormalFormat, extent, VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT | readable},
                        targets.normalRoughness);
  if (e.empty())
    e = gpu.createImage({kNormalFormat, extent, VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT | readable},
                        targets.geometricNormal);
  if (e.empty())
    e = gpu.createImage({kMotionFormat, extent, VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT | readable}, targets.motionVectors);
  // Storage and transfer destination too: a hook supplying the frame's colour (FrameParams::externalColor) writes it.
  if (e.empty())
    e = gpu.createImage({kHdrFormat, extent,
                         VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT | VK_IMAGE_USAGE_STORAGE_BIT |
                             VK_IMAGE_USAGE_TRANSFER_DST_BIT | readable},
                        targets.hdr);
  if (e.empty())
    e = gpu.createImage({kLdrFormat, extent, VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT | VK_IMAGE_USAGE_TRANSFER_SRC_BIT},
                        targets.ldr);
  frameRendered = false;
  return e;
}

std::string Engine::Impl::createShadowMap(uint32_t size) {
  gpu.destroy(targets.shadowMap);
  targets.shadowMapSize = size;
  return gpu.createImage({kDepthFormat,
                          {size, size},
                          VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT | VK_IMAGE_USAGE_SAMPLED_BIT,
                          VK_IMAGE_ASPECT_DEPTH_BIT},
                         targets.shadowMap);
}

void Engine::Impl::destroyTargets() {
  for (Image* i :
       {&targets.depth, &targets.normalRoughness, &targets.geometricNormal, &targets.motionVectors, &targets.hdr,
        &targets.ldr, &targets.ssaoRaw, &targets.ssao, &targets.shadowVisibility, &targets.localIrradiance})
    gpu.destroy(*i);
  destroyOverlayFramebuffer();
  ssaoRendered = shadowVisibilityRendered = localIrradianceRendered = false;
  targets.extent = {};
}

Status Engine::setRenderSize(uint32_t width, uint32_t height) {
  if (width == 0 || height == 0 || width > 16384 || height > 16384)
    return Status::failure("setRenderSize: invalid size " + std::to_string(width) + "x" + std::to_string(height));
  if (impl_->swapchain.swapchain) return Status::failure("setRenderSize: the size follows the swapchain");
  vkDeviceWaitIdle(impl_->ctx.device);
  std::string e = impl_->createTargets({width, height});
  return e.empty() ? Status::success() : Status::failure("render targets: " + e);
}

// ---------------------------------------------------------------------------------------------------------
// Frames, timings

std::string Engine::Impl::waitFrame(FrameResources& frame) {
  if (frame.inFlight) {
    // Only a submitted frame: the fence of one whose submit failed would never signal.
    if (VkResult r = ctx.waitForFences(ctx.device, 1, &frame.fence, VK_TRUE, UINT64_MAX); r != VK_SUCCESS)
      return gpuFailure("vkWaitForFences (frame slot)", r);
    frame.inFlight = false;
  }
  collectTimings(frame);
  return {};
}

std::string Engine::Impl::gpuFailure(const char* what, VkResult r) {
  if (r == VK_ERROR_DEVICE_LOST) deviceLost = true;
  return vkFailure(what, r);
}

std::string Engine::Impl::lostDeviceError(const char* call) const {
  return std::string(call) + ": the device was lost earlier (VK_ERROR_DEVICE_LOST); nothing more can be rendered "
                             "with it: destroy the engine and create a new one";
}

void Engine::Impl::collectTimings(FrameResources& frame) {
  const double deformMs = deformer.collectTimings(uint32_t(&frame - frames.data()));
  if (!frame.timingsPending || !frame.timestamps) return;
  frame.timingsPending = false;
  uint64_t ts[kTsCount];
  if (vkGetQueryPoolResults(ctx.device, frame.timestamps, 0, kTsCount, sizeof(ts), ts, sizeof(uint64_t),
                            VK_QUERY_RESULT_64_BIT) != VK_SUCCESS)
    return;
  // Frames can be collected out of order (waitIdle sorts, but a late fence wait may not): keep the newest.
  if (timings.valid && frame.frameNumber < timingsFrameNumber) return;
  timingsFrameNumber = frame.frameNumber;
  auto ms = [&](TimestampSlot a, TimestampSlot b) { return double(ts[b] - ts[a]) * ctx.timestampPeriodNs * 1e-6; };
  timings.shadowMs = ms(kTsStart, kTsShadowEnd);
  timings.probeMs = ms(kTsShadowEnd, kTsProbeEnd);
  timings.prepassMs = ms(kTsProbeEnd, kTsPrepassEnd);
  timings.ssaoMs = ms(kTsPrepassEnd, kTsSsaoEnd);
  timings.shadowVisibilityMs = ms(kTsSsaoEnd, kTsShadowVisibilityEnd);
  timings.hookMs = ms(kTsShadowVisibilityEnd, kTsHookEnd);
  timings.localShadowMs = ms(kTsHookEnd, kTsLocalShadowEnd);
  timings.localIrradianceMs = ms(kTsLocalShadowEnd, kTsLocalIrradianceEnd);
  timings.lightingMs = ms(kTsLocalIrradianceEnd, kTsLightingEnd);
  timings.tonemapMs = ms(kTsLightingEnd, kTsTonemapEnd);
  timings.deformMs = deformMs;
  timings.probeCaptured = frame.probeCaptured;
  timings.frameNumber = frame.frameNumber;
  timings.valid = true;
}

Status Engine::waitIdle() {
  if (impl_->deviceLost) return Status::failure(impl_->lostDeviceError("waitIdle"));
  // Oldest first, so the newest frame's timings win.
  std::array<FrameResources*, kFramesInFlight> order;
  for (uint32_t i = 0; i < kFramesInFlight; ++i) order[i] = &impl_->frames[i];
  std::sort(order.begin(), order.end(), [](auto* a, auto* b) { return a->frameNumber < b->frameNumber; });
  for (FrameResources* f : order)
    if (std::string e = impl_->waitFrame(*f); !e.empty()) return Status::failure(e);
  VkResult r = vkDeviceWaitIdle(impl_->ctx.device);
  if (r != VK_SUCCESS) return Status::failure(impl_->gpuFailure("vkDeviceWaitIdle", r));
  // Every submission is done, so every wait a hook left for the next deformation is met: dropping them lets
  // the add-on that owns their semaphores (e.g. an adapter being destroyed) release them.
  impl_->deformer.pendingWaits().clear();
  return Status::success();
}

Status Engine::renderFrame(const FrameParams& params) {
  try {
    std::string e = impl_->renderFrame(params);
    return e.empty() ? Status::success() : Status::failure(e);
  } catch (const std::exception& ex) {
    return Status::failure(std::string("renderFrame: ") + ex.what());
  }
}

// ---------------------------------------------------------------------------------------------------------
// Readback

namespace {

float halfToFloat(uint16_t h) {
  uint32_t sign = uint32_t(h >> 15) << 31, exp = (h >> 10) & 0x1f, mant = h & 0x3ff, bits;
  if (exp == 0) {
    if (mant == 0) bits = sign;
    else {  // subnormal: renormalize
      exp = 127 - 15 + 1;
      while (!(mant & 0x400)) {
        mant <<= 1;
        --exp;
      }
      bits = sign | (exp << 23) | ((mant & 0x3ff) << 13);
    }
  } else if (exp == 31)
    bits = sign | 0x7f800000u | (mant << 13);
  else
    bits = sign | ((exp + 127 - 15) << 23) | (mant << 13);
  float f;
  std::memcpy(&f, &bits, 4);
  return f;
}

// Copies `image` (in `layout`, left in it afterwards) to host memory.
std::string readImage(Engine::Impl& impl, const Image& image, VkImageLayout layout, VkDeviceSize texelSize,
                      std::vector<uint8_t>& out) {
  const VkDeviceSize size = VkDeviceSize(image.extent.width) * image.extent.height * texelSize;
  Buffer buffer;
  if (std::string e = impl.gpu.createBuffer(size, VK_BUFFER_USAGE_TRANSFER_DST_BIT,
                                            VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT | VK_MEMORY_PROPERTY_HOST_COHERENT_BIT,
                                            buffer);
      !e.empty())
    return e;
  std::string e = impl.gpu.submitNow([&](VkCommandBuffer cmd) {
    if (layout != VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL)
      imageBarrier(cmd, image.image, VK_IMAGE_ASPECT_COLOR_BIT, layout, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL,
                   VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT, VK_ACCESS_2_MEMORY_WRITE_BIT,
                   VK_PIPELINE_STAGE_2_ALL_TRANSFER_BIT, VK_ACCESS_2_TRANSFER_READ_BIT);
    VkBufferImageCopy copy{};
    copy.imageSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 0, 1};
    copy.imageExtent = {image.extent.width, image.extent.height, 1};
    vkCmdCopyImageToBuffer(cmd, image.image, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, buffer.buffer, 1, &copy);
    if (layout != VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL)
      imageBarrier(cmd, image.image, VK_IMAGE_ASPECT_COLOR_BIT, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, layout,
                   VK_PIPELINE_STAGE_2_ALL_TRANSFER_BIT, 0, VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT, 0);
    memoryBarrier(cmd, VK_PIPELINE_STAGE_2_ALL_TRANSFER_BIT, VK_ACCESS_2_TRANSFER_WRITE_BIT,
                  VK_PIPELINE_STAGE_2_HOST_BIT, VK_ACCESS_2_HOST_READ_BIT);
  });
  if (e.empty()) {
    out.resize(size);
    std::memcpy(out.data(), buffer.mapped, size);
  }
  impl.gpu.destroy(buffer);
  return e;
}

// Reads a 16-bit float image of N channels (in SHADER_READ_ONLY_OPTIMAL, left so) as floats, row-major.
template <glm::length_t N>
std::string readHalfImage(Engine::Impl& impl, const Image& image, std::vector<glm::vec<N, float>>& out) {
  std::vector<uint8_t> raw;
  if (std::string e = readImage(impl, image, VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL, 2 * N, raw); !e.empty())
    return e;
  out.resize(raw.size() / (2 * N));
  for (size_t i = 0; i < out.size(); ++i)
    for (glm::length_t c = 0; c < N; ++c) {
      uint16_t h;
      std::memcpy(&h, &raw[(i * N + size_t(c)) * 2], 2);
      out[i][c] = halfToFloat(h);
    }
  return {};
}

}  // namespace

Result<ImageRGBA8> Engine::readbackLdr() {
  using R = Result<ImageRGBA8>;
  if (Status s = waitIdle(); !s) return R::failure(s.error);
  if (!impl_->frameRendered) return R::failure("readbackLdr: no frame has been rendered");
  ImageRGBA8 img;
  img.width = impl_->targets.extent.width;
  img.height = impl_->targets.extent.height;
  // The tonemap pass leaves the LDR image in TRANSFER_SRC_OPTIMAL.
  if (std::string e = readImage(*impl_, impl_->targets.ldr, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, 4, img.pixels);
      !e.empty())
    return R::failure("readbackLdr: " + e);
  return R::success(std::move(img));
}

Result<ImageRGBA32F> Engine::readbackHdr() {
  using R = Result<ImageRGBA32F>;
  if (Status s = waitIdle(); !s) return R::failure(s.error);
  if (!impl_->frameRendered) return R::failure("readbackHdr: no frame has been rendered");
  std::vector<uint8_t> raw;
  if (std::string e = readImage(*impl_, impl_->targets.hdr, VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL, 8, raw);
      !e.empty())
    return R::failure("readbackHdr: " + e);
  ImageRGBA32F img;
  img.width = impl_->targets.extent.width;
  img.height = impl_->targets.extent.height;
  img.pixels.resize(raw.size() / 2);
  for (size_t i = 0; i < img.pixels.size(); ++i) {
    uint16_t h;
    std::memcpy(&h, &raw[i * 2], 2);
    img.pixels[i] = halfToFloat(h);
  }
  return R::success(std::move(img));
}

namespace {

// Reads an effect image (kEffectFormat, SHADER_READ_ONLY_OPTIMAL) of the last frame as floats.
Result<std::vector<float>> readEffectImage(Engine& engine, Engine::Impl& impl, const Image& image, bool rendered,
                                           const char* what) {
  using R = Result<std::vector<float>>;
  if (Status s = engine.waitIdle(); !s) return R::failure(s.error);
  if (!impl.frameRendered || !rendered || !image.image)
    return R::failure(std::string(what) + ": the last frame did not produce it");
  std::vector<uint8_t> raw;
  if (std::string e = readImage(impl, image, VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL, 2, raw); !e.empty())
    return R::failure(std::string(what) + ": " + e);
  std::vector<float> out(raw.size() / 2);
  for (size_t i = 0; i < out.size(); ++i) {
    uint16_t h;
    std::memcpy(&h, &raw[i * 2], 2);
    out[i] = halfToFloat(h);
  }
  return R::success(std::move(out));
}

}  // namespace

Result<std::vector<float>> Engine::readbackShadowVisibility() {
  return readEffectImage(*this, *impl_, impl_->targets.shadowVisibility, impl_->shadowVisibilityRendered,
                         "readbackShadowVisibility");
}

Result<std::vector<float>> Engine::readbackSsao() {
  return readEffectImage(*this, *impl_, impl_->targets.ssao, impl_->ssaoRendered, "readbackSsao");
}

Result<std::vector<glm::vec4>> Engine::readbackLocalLightIrradiance() {
  using R = Result<std::vector<glm::vec4>>;
  if (Status s = waitIdle(); !s) return R::failure(s.error);
  if (!impl_->frameRendered || !impl_->localIrradianceRendered)
    return R::failure("readbackLocalLightIrradiance: the last frame did not produce it; set "
                      "FrameParams::outputLocalLightIrradiance");
  std::vector<glm::vec4> out;
  if (std::string e = readHalfImage(*impl_, impl_->targets.localIrradiance, out); !e.empty())
    return R::failure("readbackLocalLightIrradiance: " + e);
  return R::success(std::move(out));
}

Result<std::vector<glm::vec2>> Engine::readbackMotionVectors() {
  using R = Result<std::vector<glm::vec2>>;
  if (Status s = waitIdle(); !s) return R::failure(s.error);
  if (!impl_->frameRendered || !impl_->prepassRendered)
    return R::failure("readbackMotionVectors: the last frame drew no pre-pass (FrameParams::externalColor); render "
                      "one without it");
  std::vector<glm::vec2> out;
  if (std::string e = readHalfImage(*impl_, impl_->targets.motionVectors, out); !e.empty())
    return R::failure("readbackMotionVectors: " + e);
  return R::success(std::move(out));
}

Result<std::vector<glm::vec3>> Engine::readbackDeformedPositions(uint32_t deformedIndex) {
  using R = Result<std::vector<glm::vec3>>;
  const size_t count = impl_->deformer.instances().size();
  if (deformedIndex >= count)
    return R::failure("readbackDeformedPositions: deformed instance " + std::to_string(deformedIndex) +
                      " is out of range (the scene has " + std::to_string(count) + ")");
  if (Status s = waitIdle(); !s) return R::failure(s.error);
  std::vector<glm::vec3> out;
  if (std::string e = impl_->deformer.readbackPositions(deformedIndex, out); !e.empty())
    return R::failure("readbackDeformedPositions: " + e);
  return R::success(std::move(out));
}

}  // namespace sample_engine
