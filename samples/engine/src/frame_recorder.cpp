// One frame: shadow map -> [probe capture] -> pre-pass -> [SSAO] -> [shadow visibility] -> hook -> [local
// shadow maps] -> [local-light irradiance] -> lighting (opaque, then blended) -> tonemap (-> blit to the swapchain).
#include <algorithm>
#include <cstring>

#include <glm/gtc/matrix_transform.hpp>

#include "engine_impl.h"
#include "render_utils.h"
#include "vk_check.h"

namespace sample_engine {

using namespace detail;

namespace {

constexpr VkImageLayout kDepthReadLayout = VK_IMAGE_LAYOUT_DEPTH_READ_ONLY_OPTIMAL;
constexpr VkImageLayout kReadLayout = VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL;

// Orthographic sun camera enclosing the scene's bounding sphere, looking along -direction, for positions
// relative to `origin` (the camera, or the reflection probe): the sphere's centre is rebased in double, so
// the matrix carries only a small translation wherever the scene is.
glm::mat4 lightViewProjection(const Bounds& bounds, const glm::vec3& towardsSun, const glm::dvec3& origin,
                              float& radius) {
  const glm::vec3 center(bounds.valid() ? glm::dvec3(bounds.center()) - origin : -origin);
  radius = bounds.valid() ? std::max(bounds.radius(), 1e-3f) : 1.0f;
  glm::vec3 l = glm::normalize(towardsSun);
  glm::vec3 up = std::abs(l.y) > 0.99f ? glm::vec3(0, 0, 1) : glm::vec3(0, 1, 0);
  glm::mat4 view = glm::lookAtRH(center + l * (radius * 1.5f), center, up);
  glm::mat4 proj = glm::orthoRH_ZO(-radius, radius, -radius, radius, 0.0f, radius * 3.0f);
  return proj * view;
}

}  // namespace

std::string Engine::Impl::writePreviousModels(FrameResources& frame, const glm::dvec3& eye) {
  scene.previousModels = 0;
  if (!sceneLoaded || scene.instanceTransforms.empty() || !ctx.bufferDeviceAddressFeature) return {};
  if (previousTransforms.size() != scene.instanceTransforms.size()) previousTransforms = scene.instanceTransforms;
  const VkDeviceSize bytes = VkDeviceSize(previousTransforms.size()) * sizeof(glm::mat4);
  if (frame.previousModels.size < bytes) {
    gpu.destroy(frame.previousModels);  // this slot's previous frame is done (waitFrame)
    if (std::string e = gpu.createBuffer(bytes,
                                         VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | VK_BUFFER_USAGE_SHADER_DEVICE_ADDRESS_BIT,
                                         VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT | VK_MEMORY_PROPERTY_HOST_COHERENT_BIT,
                                         frame.previousModels);
        !e.empty())
      return "previous model matrices: " + e;
  }
  auto* models = static_cast<glm::mat4*>(frame.previousModels.mapped);
  for (size_t i = 0; i < previousTransforms.size(); ++i) models[i] = rebasedTransform(previousTransforms[i], eye);
  scene.previousModels = frame.previousModels.address;
  return {};
}

std::string Engine::Impl::renderFrame(const FrameParams& params) {
  if (deviceLost) return lostDeviceError("renderFrame");
  if (targets.extent.width == 0) return "renderFrame: no render size (call setRenderSize or attachSurface)";
  static const Scene kNoScene;
  if (Status s = checkPlayback(sceneLoaded ? scene.cpu : kNoScene, params.time, params.animations); !s)
    return "renderFrame: " + s.error;
  // Without a shadow map a 1x1 placeholder stays bound (the shaders skip it: 0 PCF taps), so every
  // pipeline's descriptor sets keep their layout and the big map's memory is released.
  const bool shadowsOn = params.shadow.enabled;
  const uint32_t shadowSize = shadowsOn ? std::clamp(params.shadow.mapSize, kMinShadowMapSize, kMaxShadowMapSize) : 1u;
  const uint32_t taps = shadowsOn ? std::clamp(params.shadow.pcfKernelSize, 1u, kMaxShadowPcfKernel) : 0u;
  if (shadowSize != targets.shadowMapSize) {
    vkDeviceWaitIdle(ctx.device);  // frames in flight may still sample the old map
    if (std::string e = createShadowMap(shadowSize); !e.empty()) return "shadow map: " + e;
  }
  const uint32_t probeResolution = ReflectionProbe::clampResolution(params.reflectionProbe.resolution);
  if (params.reflectionProbe.enabled)
    if (std::string e = probe.prepare(probeResolution); !e.empty()) return "reflection probe: " + e;
  if (params.externalColor && (params.outputLocalLightIrradiance || params.outputShadowVisibility))
    return std::string(
               "renderFrame: FrameParams::externalColor leaves the shading to the hook, so the engine has no ") +
           (params.outputShadowVisibility ? "outputShadowVisibility" : "outputLocalLightIrradiance") + " to write";
  if (std::string e = ensureEffectImages(params); !e.empty()) return "effect images: " + e;
  if (std::string e = prepareLocalShadowMaps(params.localLights); !e.empty()) return "local shadow maps: " + e;
  if (params.outputLocalLightIrradiance && !targets.localIrradiance.image)
    if (std::string e = gpu.createImage({kNormalFormat, targets.extent,
                                         VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT | VK_IMAGE_USAGE_SAMPLED_BIT |
                                             VK_IMAGE_USAGE_TRANSFER_SRC_BIT},
                                        targets.localIrradiance);
        !e.empty())
      return "local-light irradiance image: " + e;
  if (std::string e = prepareOverlay(); !e.empty()) return "overlay: " + e;
  const uint32_t slot = currentFrame;
  FrameResources& frame = frames[slot];
  if (std::string e = waitFrame(frame); !e.empty()) return e;

  std::optional<uint32_t> imageIndex;
  if (swapchain.swapchain) {
    uint32_t index = 0;
    VkResult r = vkAcquireNextImageKHR(ctx.device, swapchain.swapchain, UINT64_MAX, frame.imageAcquired, VK_NULL_HANDLE,
                                       &index);
    if (r == VK_ERROR_OUT_OF_DATE_KHR) return createSwapchain(swapchain.extent.width, swapchain.extent.height);
    if (r != VK_SUCCESS && r != VK_SUBOPTIMAL_KHR) return vkFailure("vkAcquireNextImageKHR", r);
    imageIndex = index;
  }

  // --- Animation: this frame's pose on the CPU, then the deformed vertex buffers in their own submission ---
  const uint64_t frameNumber = frameCounter + 1;
  if (sceneLoaded) {
    if (Status s = pose.evaluate(scene.cpu, params.time, params.animations, params.restPose); !s)
      return "renderFrame: " + s.error;
    const std::span<const glm::mat4> transforms = pose.instanceTransforms();
    std::copy(transforms.begin(), transforms.end(), scene.instanceTransforms.begin());
    if (deformer.active())
      if (std::string e = deformer.submit(slot, frameNumber, pose); !e.empty()) return "renderFrame: " + e;
  }
  // The KHR lights follow their nodes; off, they are not drawn and the hook sees none.
  if (sceneLoaded && params.localLights.enabled) placeLights(scene.cpu, pose.nodeWorld(), frameLights);
  else
    frameLights.clear();

  // --- Uniforms ---
  const VkExtent2D extent = targets.extent;
  const Bounds bounds = sceneLoaded ? scene.bounds : Bounds{};
  // Camera-relative raster: draws rebase their model matrices to the eye in double (drawScene), the view is
  // rotation only, and every position the shaders see is relative to the eye. A world-space viewProj in float
  // would lose about |eye| * 2^-24 per operation (1 mm at 20 km), amplified by the perspective divide.
  const glm::dvec3 eye(params.camera.eye);
  FrameUniforms u{};
  u.view = viewMatrix(params.camera);
  u.view[3] = glm::vec4(0.0f, 0.0f, 0.0f, 1.0f);
  u.proj = projectionMatrix(params.camera, float(extent.width) / float(extent.height));
  u.viewProj = u.proj * u.view;
  u.invViewProj = glm::inverse(u.viewProj);
  float lightRadius = 1.0f;
  u.lightViewProj = lightViewProjection(bounds, params.sun.direction, eye, lightRadius);
  u.cameraPos = glm::vec4(params.camera.eye, 1.0f);
  u.sunDirection = glm::vec4(glm::normalize(params.sun.direction), 0.0f);
  u.sunRadiance = glm::vec4(params.sun.color * params.sun.intensity, 0.0f);
  u.sky = glm::vec4(params.skyColor, params.ambientIntensity);
  u.viewport = glm::vec4(extent.width, extent.height, 1.0f / extent.width, 1.0f / extent.height);
  // The normal offset grows by the kernel's reach ((taps - 1) / 2 texels): on a slope facing the sun at an
  // angle, the outer taps of a wide kernel would otherwise compare against the receiver's own depth.
  const float normalOffsetTexels = params.shadow.normalOffset + 0.5f * float(std::max(taps, 1u) - 1u);
  u.shadow = glm::vec4(1.0f / float(shadowSize), float(taps),
                       shadowsOn ? normalOffsetTexels * 2.0f * lightRadius / float(shadowSize) : 0.0f, 0.0f);
  u.invProj = glm::inverse(u.proj);
  // Last frame's camera rebased to this eye (the motion vectors' camera part); none yet: this frame's, no motion.
  u.previousViewProj = hasPreviousCamera
                           ? previousProj * previousView * glm::translate(glm::mat4(1.0f), glm::vec3(eye - previousEye))
                           : u.viewProj;
  if (std::string e = writePreviousModels(frame, eye); !e.empty()) return "renderFrame: " + e;
  // inputs and probe are filled after the hook; the uniform buffer is written before submission.

  // The probe is static: captured again only when something it depends on changed.
  ProbeKey probeKey;
  bool captureProbe = false;
  if (params.reflectionProbe.enabled && !params.externalColor) {
    // Its light matrix is relative to the probe, not the camera: moving the camera does not recapture.
    const glm::vec3 probePosition = ReflectionProbe::positionFor(params.reflectionProbe, bounds);
    float probeLightRadius = 1.0f;
    probeKey = ProbeKey{sceneVersion,
                        probeResolution,
                        probePosition,
                        u.sunDirection,
                        u.sunRadiance,
                        u.sky,
                        u.shadow,
                        lightViewProjection(bounds, params.sun.direction, glm::dvec3(probePosition), probeLightRadius),
                        params.shadow.depthBiasConstant,
                        params.shadow.depthBiasSlope};
    captureProbe = probe.needsCapture(probeKey);
  }

  SE_VK_TRY(vkResetCommandBuffer(frame.cmd, 0));
  VkCommandBufferBeginInfo bi{VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO};
  bi.flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT;
  SE_VK_TRY(vkBeginCommandBuffer(frame.cmd, &bi));
  frame.frameNumber = ++frameCounter;
  submitWaits.clear();
  recordFrame(frame, params, u, imageIndex, captureProbe, probeKey);
  SE_VK_TRY(vkEndCommandBuffer(frame.cmd));

  // --- Submit (and present) ---
  VkCommandBufferSubmitInfo cbi{VK_STRUCTURE_TYPE_COMMAND_BUFFER_SUBMIT_INFO};
  cbi.commandBuffer = frame.cmd;
  mainWaits.clear();
  if (imageIndex) {
    VkSemaphoreSubmitInfo w{VK_STRUCTURE_TYPE_SEMAPHORE_SUBMIT_INFO};
    w.semaphore = frame.imageAcquired;
    w.stageMask = VK_PIPELINE_STAGE_2_ALL_TRANSFER_BIT;  // only the final blit touches the image
    mainWaits.push_back(w);
  }
  if (sceneLoaded && deformer.active()) {
    // Same queue: makes this frame's deformed buffers visible to every pass (and AS build) of the frame.
    VkSemaphoreSubmitInfo w{VK_STRUCTURE_TYPE_SEMAPHORE_SUBMIT_INFO};
    w.semaphore = deformer.semaphore();
    w.value = frame.frameNumber;
    w.stageMask = VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT;
    mainWaits.push_back(w);
  }
  mainWaits.insert(mainWaits.end(), submitWaits.begin(), submitWaits.end());
  VkSemaphoreSubmitInfo signalInfo{VK_STRUCTURE_TYPE_SEMAPHORE_SUBMIT_INFO};
  signalInfo.stageMask = VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT;
  VkSubmitInfo2 si{VK_STRUCTURE_TYPE_SUBMIT_INFO_2};
  si.commandBufferInfoCount = 1;
  si.pCommandBufferInfos = &cbi;
  si.waitSemaphoreInfoCount = uint32_t(mainWaits.size());
  si.pWaitSemaphoreInfos = mainWaits.data();
  if (imageIndex) {
    signalInfo.semaphore = swapchain.renderFinished[*imageIndex];
    si.signalSemaphoreInfoCount = 1;
    si.pSignalSemaphoreInfos = &signalInfo;
  }
  SE_VK_TRY(vkResetFences(ctx.device, 1, &frame.fence));
  if (VkResult r = ctx.queueSubmit2(ctx.queue, 1, &si, frame.fence); r != VK_SUCCESS)
    return gpuFailure("vkQueueSubmit2 (frame)", r);
  frame.inFlight = true;
  frame.timingsPending = frame.timestamps != VK_NULL_HANDLE;
  lastSubmittedSlot = slot;
  currentFrame = (currentFrame + 1) % kFramesInFlight;
  frameRendered = true;
  // This frame is the next one's "previous" (motion vectors).
  if (sceneLoaded) previousTransforms = scene.instanceTransforms;
  hasPreviousCamera = true;
  previousEye = eye;
  previousView = u.view;
  previousProj = u.proj;
  ssaoRendered = params.ssao.enabled && !params.externalColor;
  shadowVisibilityRendered = params.outputShadowVisibility;
  localIrradianceRendered = params.outputLocalLightIrradiance;
  prepassRendered = !params.externalColor;
  const bool shadowMapDrawn = shadowsOn && !params.externalColor;
  shadowStats = ShadowMapStats{shadowMapDrawn, shadowMapDrawn ? shadowSize : 0u, shadowMapDrawn ? taps : 0u,
                               frame.frameNumber};

  if (imageIndex) {
    VkPresentInfoKHR pi{VK_STRUCTURE_TYPE_PRESENT_INFO_KHR};
    pi.waitSemaphoreCount = 1;
    pi.pWaitSemaphores = &swapchain.renderFinished[*imageIndex];
    pi.swapchainCount = 1;
    pi.pSwapchains = &swapchain.swapchain;
    pi.pImageIndices = &*imageIndex;
    VkResult r = vkQueuePresentKHR(ctx.queue, &pi);
    if (r == VK_ERROR_OUT_OF_DATE_KHR || r == VK_SUBOPTIMAL_KHR)
      return createSwapchain(swapchain.extent.width, swapchain.extent.height);
    if (r != VK_SUCCESS) return vkFailure("vkQueuePresentKHR", r);
  }
  return {};
}

void Engine::Impl::recordFrame(FrameResources& frame, const FrameParams& params, const FrameUniforms& uniformsIn,
                               std::optional<uint32_t> swapchainImage, bool captureProbe, const ProbeKey& probeKey) {
  VkCommandBuffer cmd = frame.cmd;
  const VkExtent2D extent = targets.extent;
  const bool haveScene = sceneLoaded;
  const glm::dvec3 eye(params.camera.eye);  // drawScene rebases every model matrix to it
  auto timestamp = [&](TimestampSlot s) {
    if (frame.timestamps) vkCmdWriteTimestamp2(cmd, VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT, frame.timestamps, s);
  };
  if (frame.timestamps) vkCmdResetQueryPool(cmd, frame.timestamps, 0, kTsCount);
  timestamp(kTsStart);
  vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, pipelines.sceneLayout, 0, 1, &frame.frameSet, 0,
                          nullptr);

  // (1) Shadow map. Previous contents are discarded (UNDEFINED); the barrier also orders this write after
  // the previous frame's sampling. Without a shadow map only the placeholder's layout is set for binding.
  // With an external colour nothing samples the map: it is only put in its read layout, as without one.
  const bool external = params.externalColor;
  if (!params.shadow.enabled || external) {
    imageBarrier(cmd, targets.shadowMap.image, VK_IMAGE_ASPECT_DEPTH_BIT, VK_IMAGE_LAYOUT_UNDEFINED, kReadLayout,
                 VK_PIPELINE_STAGE_2_FRAGMENT_SHADER_BIT, 0, VK_PIPELINE_STAGE_2_FRAGMENT_SHADER_BIT,
                 VK_ACCESS_2_SHADER_SAMPLED_READ_BIT);
  } else {
    imageBarrier(cmd, targets.shadowMap.image, VK_IMAGE_ASPECT_DEPTH_BIT, VK_IMAGE_LAYOUT_UNDEFINED,
                 VK_IMAGE_LAYOUT_DEPTH_ATTACHMENT_OPTIMAL, VK_PIPELINE_STAGE_2_FRAGMENT_SHADER_BIT, 0,
                 VK_PIPELINE_STAGE_2_EARLY_FRAGMENT_TESTS_BIT | VK_PIPELINE_STAGE_2_LATE_FRAGMENT_TESTS_BIT,
                 VK_ACCESS_2_DEPTH_STENCIL_ATTACHMENT_READ_BIT | VK_ACCESS_2_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT);
    VkRenderingAttachmentInfo depth{VK_STRUCTURE_TYPE_RENDERING_ATTACHMENT_INFO};
    depth.imageView = targets.shadowMap.view;
    depth.imageLayout = VK_IMAGE_LAYOUT_DEPTH_ATTACHMENT_OPTIMAL;
    depth.loadOp = VK_ATTACHMENT_LOAD_OP_CLEAR;
    depth.storeOp = VK_ATTACHMENT_STORE_OP_STORE;
    depth.clearValue.depthStencil = {1.0f, 0};
    beginRendering(cmd, {targets.shadowMapSize, targets.shadowMapSize}, {}, &depth);
    vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, pipelines.shadow);
    vkCmdSetDepthBias(cmd, params.shadow.depthBiasConstant, 0.0f, params.shadow.depthBiasSlope);
    if (haveScene) drawScene(cmd, scene, pipelines, DrawPass::Shadow, {}, eye);
    vkCmdEndRendering(cmd);
    imageBarrier(cmd, targets.shadowMap.image, VK_IMAGE_ASPECT_DEPTH_BIT, VK_IMAGE_LAYOUT_DEPTH_ATTACHMENT_OPTIMAL,
                 kReadLayout, VK_PIPELINE_STAGE_2_LATE_FRAGMENT_TESTS_BIT,
                 VK_ACCESS_2_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT, VK_PIPELINE_STAGE_2_FRAGMENT_SHADER_BIT,
                 VK_ACCESS_2_SHADER_SAMPLED_READ_BIT);
  }
  timestamp(kTsShadowEnd);

  // (1b) Reflection probe: six forward-shaded faces + mips, only when its inputs changed. It uses this
  // frame's shadow map (already in its read layout) and binds its own set 0, so ours is rebound after.
  frame.probeCaptured = captureProbe;
  if (captureProbe) {
    probe.recordCapture(cmd, uint32_t(&frame - frames.data()), uniformsIn, probeKey, haveScene ? &scene : nullptr,
                        targets.shadowMap.view, defaults, localLightBindings(frame));
    vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, pipelines.sceneLayout, 0, 1, &frame.frameSet, 0,
                            nullptr);
  }
  timestamp(kTsProbeEnd);

  // (2) Depth + normal pre-pass. The previous frame's readers may include the hook's own passes (any
  // stage), hence ALL_COMMANDS as the source scope.
  imageBarrier(cmd, targets.depth.image, VK_IMAGE_ASPECT_DEPTH_BIT, VK_IMAGE_LAYOUT_UNDEFINED,
               VK_IMAGE_LAYOUT_DEPTH_ATTACHMENT_OPTIMAL, VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT, 0,
               VK_PIPELINE_STAGE_2_EARLY_FRAGMENT_TESTS_BIT | VK_PIPELINE_STAGE_2_LATE_FRAGMENT_TESTS_BIT,
               VK_ACCESS_2_DEPTH_STENCIL_ATTACHMENT_READ_BIT | VK_ACCESS_2_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT);
  for (const Image* img : {&targets.normalRoughness, &targets.geometricNormal, &targets.motionVectors})
    imageBarrier(cmd, img->image, VK_IMAGE_ASPECT_COLOR_BIT, VK_IMAGE_LAYOUT_UNDEFINED,
                 VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL, VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT, 0,
                 VK_PIPELINE_STAGE_2_COLOR_ATTACHMENT_OUTPUT_BIT, VK_ACCESS_2_COLOR_ATTACHMENT_WRITE_BIT);
  {
    VkRenderingAttachmentInfo depth{VK_STRUCTURE_TYPE_RENDERING_ATTACHMENT_INFO};
    depth.imageView = targets.depth.view;
    depth.imageLayout = VK_IMAGE_LAYOUT_DEPTH_ATTACHMENT_OPTIMAL;
    depth.loadOp = VK_ATTACHMENT_LOAD_OP_CLEAR;
    depth.storeOp = VK_ATTACHMENT_STORE_OP_STORE;
    depth.clearValue.depthStencil = {1.0f, 0};
    beginRendering(cmd, extent,
                   {colorAttachment(targets.normalRoughness.view, {}),
                    colorAttachment(targets.geometricNormal.view, {}), colorAttachment(targets.motionVectors.view, {})},
                   &depth);
    // BLEND surfaces stay out: depth and normals (and what the hook computes from them) are the opaque scene's.
    if (haveScene && !external)
      drawScene(cmd, scene, pipelines, DrawPass::Prepass, {pipelines.prepass, pipelines.prepassMasked}, eye);
    vkCmdEndRendering(cmd);
  }
  // Readable by anything the hook records; depth stays usable as the lighting pass's read-only attachment.
  imageBarrier(cmd, targets.depth.image, VK_IMAGE_ASPECT_DEPTH_BIT, VK_IMAGE_LAYOUT_DEPTH_ATTACHMENT_OPTIMAL,
               kDepthReadLayout, VK_PIPELINE_STAGE_2_LATE_FRAGMENT_TESTS_BIT,
               VK_ACCESS_2_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT, VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT,
               VK_ACCESS_2_SHADER_READ_BIT | VK_ACCESS_2_DEPTH_STENCIL_ATTACHMENT_READ_BIT |
                   VK_ACCESS_2_TRANSFER_READ_BIT);
  for (const Image* img : {&targets.normalRoughness, &targets.geometricNormal, &targets.motionVectors})
    imageBarrier(cmd, img->image, VK_IMAGE_ASPECT_COLOR_BIT, VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL, kReadLayout,
                 VK_PIPELINE_STAGE_2_COLOR_ATTACHMENT_OUTPUT_BIT, VK_ACCESS_2_COLOR_ATTACHMENT_WRITE_BIT,
                 VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT, VK_ACCESS_2_SHADER_READ_BIT | VK_ACCESS_2_TRANSFER_READ_BIT);
  timestamp(kTsPrepassEnd);

  // (2b) The engine's own screen-space effects. SSAO runs whenever enabled (also next to an external AO
  // input, so both can be read back from one frame); the shadow-visibility image only on request.
  if (params.ssao.enabled && !external) recordSsao(frame, params.ssao);
  timestamp(kTsSsaoEnd);
  if (params.outputShadowVisibility) recordShadowVisibility(frame);
  timestamp(kTsShadowVisibilityEnd);

  // (3) Extension point. With an external colour the hook gets the HDR target, cleared to the sky (the previous
  // frame's tonemap may still read it).
  if (external) {
    imageBarrier(cmd, targets.hdr.image, VK_IMAGE_ASPECT_COLOR_BIT, VK_IMAGE_LAYOUT_UNDEFINED, VK_IMAGE_LAYOUT_GENERAL,
                 VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT, 0, VK_PIPELINE_STAGE_2_CLEAR_BIT,
                 VK_ACCESS_2_TRANSFER_WRITE_BIT);
    const VkClearColorValue sky{{params.skyColor.r, params.skyColor.g, params.skyColor.b, 1.0f}};
    const VkImageSubresourceRange all{VK_IMAGE_ASPECT_COLOR_BIT, 0, 1, 0, 1};
    vkCmdClearColorImage(cmd, targets.hdr.image, VK_IMAGE_LAYOUT_GENERAL, &sky, 1, &all);
    imageBarrier(cmd, targets.hdr.image, VK_IMAGE_ASPECT_COLOR_BIT, VK_IMAGE_LAYOUT_GENERAL, VK_IMAGE_LAYOUT_GENERAL,
                 VK_PIPELINE_STAGE_2_CLEAR_BIT, VK_ACCESS_2_TRANSFER_WRITE_BIT, VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT,
                 VK_ACCESS_2_MEMORY_READ_BIT | VK_ACCESS_2_MEMORY_WRITE_BIT);
  }
  LightingInputs inputs = params.lightingInputs;
  if (hook) {
    PrepassHookInfo info;
    info.commandBuffer = cmd;
    info.frameIndex = uint32_t(&frame - frames.data());
    info.frameNumber = frame.frameNumber;
    info.extent = extent;
    info.depth = {targets.depth.image, targets.depth.view, kDepthFormat, kDepthReadLayout};
    info.normalRoughness = {targets.normalRoughness.image, targets.normalRoughness.view, kNormalFormat, kReadLayout};
    info.geometricNormal = {targets.geometricNormal.image, targets.geometricNormal.view, kNormalFormat, kReadLayout};
    info.motionVectors = {targets.motionVectors.image, targets.motionVectors.view, kMotionFormat, kReadLayout};
    info.reversedZ = false;
    info.view = uniformsIn.view;
    info.proj = uniformsIn.proj;
    info.viewProj = uniformsIn.viewProj;
    info.invView = glm::inverse(uniformsIn.view);
    info.invProj = glm::inverse(uniformsIn.proj);
    info.invViewProj = uniformsIn.invViewProj;
    info.cameraPosition = params.camera.eye;
    info.cameraPositionD = eye;
    info.sunDirection = glm::vec3(uniformsIn.sunDirection);
    info.sunRadiance = glm::vec3(uniformsIn.sunRadiance);
    info.skyColor = glm::vec3(uniformsIn.sky);
    info.ambientIntensity = uniformsIn.sky.w;
    if (haveScene) info.instanceTransforms = scene.instanceTransforms;
    info.lights = frameLights;
    info.deformedInstances = deformer.instances();
    info.deformSemaphore = deformer.semaphore();
    info.deformValue = deformer.active() ? frame.frameNumber : 0;
    if (external) info.hdrColor = {targets.hdr.image, targets.hdr.view, kHdrFormat, VK_IMAGE_LAYOUT_GENERAL};
    info.submitWaits = &submitWaits;
    info.deformWaits = deformer.active() ? &deformer.pendingWaits() : nullptr;
    hook(info, inputs);
    // Whatever the hook wrote becomes visible to the lighting pass (layouts are the hook's business).
    memoryBarrier(cmd, VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT, VK_ACCESS_2_MEMORY_WRITE_BIT,
                  VK_PIPELINE_STAGE_2_FRAGMENT_SHADER_BIT | VK_PIPELINE_STAGE_2_EARLY_FRAGMENT_TESTS_BIT,
                  VK_ACCESS_2_SHADER_READ_BIT | VK_ACCESS_2_DEPTH_STENCIL_ATTACHMENT_READ_BIT);
  }
  timestamp(kTsHookEnd);

  // (3b) KHR lights, after the hook so that its LightingInputs::localLightIrradiance is known: the light
  // buffers, the shadow maps of the strongest lights (skipped under an external irradiance unless the engine's
  // own is requested) and the irradiance output. Writes kTsLocalShadowEnd and kTsLocalIrradianceEnd.
  recordLocalLights(frame, params, uniformsIn, inputs);

  // External inputs win over the engine's own SSAO; the probe stays bound under an external reflection, as
  // the environment term where the reflection's alpha (coverage) is below 1.
  const VkImageView ao = inputs.ambientOcclusion ? inputs.ambientOcclusion
                         : params.ssao.enabled   ? targets.ssao.view
                                                 : VK_NULL_HANDLE;
  const bool useProbe = params.reflectionProbe.enabled && probe.captured();
  FrameUniforms u = uniformsIn;
  u.inputs = glm::uvec4(inputs.sunVisibility != VK_NULL_HANDLE, ao != VK_NULL_HANDLE,
                        inputs.reflection != VK_NULL_HANDLE, 0u);
  u.probe = glm::vec4(useProbe ? 1.0f : 0.0f, probe.maxLod(), 0.0f, 0.0f);
  u.localLights = glm::uvec4(params.localLights.enabled ? uint32_t(frameLights.size()) : 0u,
                             inputs.localLightIrradiance != VK_NULL_HANDLE, 0u, 0u);
  std::memcpy(frame.uniforms.mapped, &u, sizeof(u));  // host-coherent; the submission makes it visible
  writeImageDescriptors(
      ctx.device, frame.lightingSet,
      {{pipelines.shadowSampler, targets.shadowMap.view, kReadLayout},
       {pipelines.screenSampler, inputs.sunVisibility ? inputs.sunVisibility : defaults.white.view, kReadLayout},
       {pipelines.screenSampler, ao ? ao : defaults.white.view, kReadLayout},
       {pipelines.screenSampler, inputs.reflection ? inputs.reflection : defaults.black.view, kReadLayout},
       {pipelines.cubeSampler, useProbe ? probe.view() : probe.fallbackView(), kReadLayout}});
  writeLocalLightDescriptors(ctx.device, pipelines, frame.lightingSet, kLightingLocalLightBinding,
                             localLightBindings(frame));
  writeImageDescriptors(ctx.device, frame.lightingSet,
                        {{pipelines.screenSampler,
                          inputs.localLightIrradiance ? inputs.localLightIrradiance : defaults.black.view,
                          kReadLayout}},
                        8);
  writeImageDescriptors(ctx.device, frame.tonemapSet, {{pipelines.nearestSampler, targets.hdr.view, kReadLayout}});

  // (4) Forward lighting: EQUAL test against the pre-pass depth, background keeps the sky clear color; then the
  // blended surfaces in the same rendering scope. With an external colour the hook's becomes the tonemap's input.
  if (external) {
    imageBarrier(cmd, targets.hdr.image, VK_IMAGE_ASPECT_COLOR_BIT, VK_IMAGE_LAYOUT_GENERAL, kReadLayout,
                 VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT, VK_ACCESS_2_MEMORY_WRITE_BIT,
                 VK_PIPELINE_STAGE_2_FRAGMENT_SHADER_BIT, VK_ACCESS_2_SHADER_SAMPLED_READ_BIT);
  } else {
    imageBarrier(cmd, targets.hdr.image, VK_IMAGE_ASPECT_COLOR_BIT, VK_IMAGE_LAYOUT_UNDEFINED,
                 VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL, VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT, 0,
                 VK_PIPELINE_STAGE_2_COLOR_ATTACHMENT_OUTPUT_BIT, VK_ACCESS_2_COLOR_ATTACHMENT_WRITE_BIT);
    {
      VkRenderingAttachmentInfo depth{VK_STRUCTURE_TYPE_RENDERING_ATTACHMENT_INFO};
      depth.imageView = targets.depth.view;
      depth.imageLayout = kDepthReadLayout;
      depth.loadOp = VK_ATTACHMENT_LOAD_OP_LOAD;
      depth.storeOp = VK_ATTACHMENT_STORE_OP_NONE;  // read-only: no write access at the end of the pass
      VkClearColorValue sky{{params.skyColor.r, params.skyColor.g, params.skyColor.b, 1.0f}};
      beginRendering(cmd, extent, {colorAttachment(targets.hdr.view, sky)}, &depth);
      // Set 0 again: the effect passes' pipeline layout (other push constants) disturbed the binding.
      vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, pipelines.sceneLayout, 0, 1, &frame.frameSet, 0,
                              nullptr);
      vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, pipelines.sceneLayout, 2, 1, &frame.lightingSet, 0,
                              nullptr);
      if (haveScene) {
        drawScene(cmd, scene, pipelines, DrawPass::Lighting, {pipelines.forward, pipelines.forwardMasked}, eye);
        // (4b) BLEND surfaces over the lit opaque scene, back to front, tested against the pre-pass depth.
        drawBlended(cmd, scene, pipelines, eye);
      }
      vkCmdEndRendering(cmd);
    }
    imageBarrier(cmd, targets.hdr.image, VK_IMAGE_ASPECT_COLOR_BIT, VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL,
                 kReadLayout, VK_PIPELINE_STAGE_2_COLOR_ATTACHMENT_OUTPUT_BIT, VK_ACCESS_2_COLOR_ATTACHMENT_WRITE_BIT,
                 VK_PIPELINE_STAGE_2_FRAGMENT_SHADER_BIT, VK_ACCESS_2_SHADER_SAMPLED_READ_BIT);
  }
  timestamp(kTsLightingEnd);

  // (5) Tonemap into the 8-bit sRGB target, left in TRANSFER_SRC_OPTIMAL for readback / swapchain blit.
  imageBarrier(cmd, targets.ldr.image, VK_IMAGE_ASPECT_COLOR_BIT, VK_IMAGE_LAYOUT_UNDEFINED,
               VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL, VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT, 0,
               VK_PIPELINE_STAGE_2_COLOR_ATTACHMENT_OUTPUT_BIT, VK_ACCESS_2_COLOR_ATTACHMENT_WRITE_BIT);
  {
    beginRendering(cmd, extent, {colorAttachment(targets.ldr.view, {})}, nullptr);
    vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, pipelines.tonemap);
    vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, pipelines.tonemapLayout, 0, 1, &frame.tonemapSet, 0,
                            nullptr);
    vkCmdPushConstants(cmd, pipelines.tonemapLayout, VK_SHADER_STAGE_FRAGMENT_BIT, 0, sizeof(float), &params.exposure);
    vkCmdDraw(cmd, 3, 1, 0, 0);
    vkCmdEndRendering(cmd);
  }
  imageBarrier(cmd, targets.ldr.image, VK_IMAGE_ASPECT_COLOR_BIT, VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL,
               VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, VK_PIPELINE_STAGE_2_COLOR_ATTACHMENT_OUTPUT_BIT,
               VK_ACCESS_2_COLOR_ATTACHMENT_WRITE_BIT, VK_PIPELINE_STAGE_2_ALL_TRANSFER_BIT,
               VK_ACCESS_2_TRANSFER_READ_BIT);
  timestamp(kTsTonemapEnd);
  if (overlayHook) recordOverlay(frame, swapchainImage);  // swapchain.cpp: UI on top of the tonemapped frame

  // (6) Present path: blit (with channel swizzle if the swapchain is BGRA) into the acquired image.
  if (swapchainImage) {
    VkImage dst = swapchain.images[*swapchainImage];
    imageBarrier(cmd, dst, VK_IMAGE_ASPECT_COLOR_BIT, VK_IMAGE_LAYOUT_UNDEFINED, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL,
                 VK_PIPELINE_STAGE_2_ALL_TRANSFER_BIT, 0, VK_PIPELINE_STAGE_2_ALL_TRANSFER_BIT,
                 VK_ACCESS_2_TRANSFER_WRITE_BIT);
    VkImageBlit blit{};
    blit.srcSubresource = blit.dstSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 0, 1};
    blit.srcOffsets[1] = {int32_t(extent.width), int32_t(extent.height), 1};
    blit.dstOffsets[1] = {int32_t(swapchain.extent.width), int32_t(swapchain.extent.height), 1};
    vkCmdBlitImage(cmd, targets.ldr.image, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, dst,
                   VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, 1, &blit, VK_FILTER_NEAREST);
    imageBarrier(cmd, dst, VK_IMAGE_ASPECT_COLOR_BIT, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL,
                 VK_IMAGE_LAYOUT_PRESENT_SRC_KHR, VK_PIPELINE_STAGE_2_ALL_TRANSFER_BIT, VK_ACCESS_2_TRANSFER_WRITE_BIT,
                 VK_PIPELINE_STAGE_2_NONE, 0);
  }
}

}  // namespace sample_engine
