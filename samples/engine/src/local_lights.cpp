// KHR lights (Scene::lights) of a frame: placement with the animated nodes, the ranking that picks the
// shadowed ones, their shadow views, the per-frame light buffers and the local shadow-map and irradiance passes.
#include "local_lights.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <numeric>

#include <glm/gtc/matrix_transform.hpp>

#include "engine_impl.h"
#include "render_utils.h"
#include "vk_check.h"

namespace sample_engine {

using namespace detail;

namespace detail {

void placeLights(const Scene& scene, std::span<const glm::mat4> nodeWorld, std::vector<FrameLight>& out) {
  out.resize(scene.lights.size());
  for (size_t i = 0; i < scene.lights.size(); ++i) {
    const PunctualLight& l = scene.lights[i];
    const glm::mat4& world = l.node >= 0 && size_t(l.node) < nodeWorld.size() ? nodeWorld[size_t(l.node)] : l.transform;
    FrameLight& f = out[i];
    f.type = l.type;
    f.light = uint32_t(i);
    f.position = glm::dvec3(world[3]);
    const glm::vec3 d = glm::mat3(world) * glm::vec3(0.0f, 0.0f, -1.0f);
    const float len = glm::length(d);
    f.direction = len > 0.0f && std::isfinite(len) ? d / len : glm::vec3(0.0f, 0.0f, -1.0f);
    f.color = l.color;
    f.intensity = l.intensity;
    f.range = l.range;
    f.innerConeAngle = l.innerConeAngle;
    f.outerConeAngle = l.outerConeAngle;
  }
}

double shadowRank(const FrameLight& light, const glm::dvec3& eye) {
  const double lum = 0.2126 * light.color.r + 0.7152 * light.color.g + 0.0722 * light.color.b;
  const double strength = lum * double(light.intensity);
  if (light.type == PunctualLight::Type::Directional) return strength;
  const glm::dvec3 d = light.position - eye;
  return strength / std::max(glm::dot(d, d), 1.0);
}

std::vector<uint32_t> strongestLights(std::span<const FrameLight> lights, const glm::dvec3& eye, uint32_t count) {
  std::vector<uint32_t> order(lights.size());
  std::iota(order.begin(), order.end(), 0u);
  std::vector<double> rank(lights.size());
  for (size_t i = 0; i < lights.size(); ++i) rank[i] = shadowRank(lights[i], eye);
  std::stable_sort(order.begin(), order.end(), [&](uint32_t a, uint32_t b) { return rank[a] > rank[b]; });
  while (!order.empty() && !(rank[order.back()] > 0.0)) order.pop_back();
  if (order.size() > count) order.resize(count);
  return order;
}

namespace {

glm::vec3 anyUp(const glm::vec3& forward) {
  return std::abs(forward.y) > 0.99f ? glm::vec3(0.0f, 0.0f, 1.0f) : glm::vec3(0.0f, 1.0f, 0.0f);
}

// Distance from `p` to the farthest corner of `bounds` (rest pose), with a margin for animation.
float reachOf(const Bounds& bounds, const glm::dvec3& p) {
  if (!bounds.valid()) return 100.0f;
  double far = 0.0;
  for (int c = 0; c < 8; ++c) {
    const glm::dvec3 corner((c & 1) ? bounds.max.x : bounds.min.x, (c & 2) ? bounds.max.y : bounds.min.y,
                            (c & 4) ? bounds.max.z : bounds.min.z);
    far = std::max(far, glm::length(corner - p));
  }
  return float(far * 1.1 + 1e-3);
}

}  // namespace

LocalShadowViews shadowViewsFor(const FrameLight& light, const Bounds& bounds, const glm::dvec3& eye, uint32_t mapSize,
                                uint32_t taps) {
  LocalShadowViews v;
  const glm::vec3 rel(light.position - eye);  // camera-relative, rebased in double
  if (light.type == PunctualLight::Type::Directional) {
    // As the sun's: an orthographic box around the scene's bounding sphere.
    const glm::vec3 center(bounds.valid() ? glm::dvec3(bounds.center()) - eye : -eye);
    const float radius = bounds.valid() ? std::max(bounds.radius(), 1e-3f) : 1.0f;
    const glm::vec3 towards = -light.direction;
    const glm::mat4 view = glm::lookAtRH(center + towards * (radius * 1.5f), center, anyUp(towards));
    v.count = 1;
    v.viewProj[0] = glm::orthoRH_ZO(-radius, radius, -radius, radius, 0.0f, radius * 3.0f) * view;
    v.footprint = 2.0f * radius / float(mapSize);
    v.orthographic = true;
    return v;
  }
  // Near/far: the range when given (nothing is lit beyond it), else the scene's farthest corner.
  const float reach = light.range > 0.0f ? std::min(light.range, reachOf(bounds, light.position))
                                         : reachOf(bounds, light.position);
  const float zFar = std::max(reach, 1e-2f), zNear = std::max(zFar * 1e-3f, 1e-3f);
  if (light.type == PunctualLight::Type::Spot && light.outerConeAngle <= kMaxSingleViewSpotCone) {
    // The outer cone plus the kernel's reach, so the PCF taps at the cone's edge stay inside the map.
    const float tanHalf = std::tan(light.outerConeAngle) * (1.0f + 2.0f * float(taps + 1) / float(mapSize));
    const glm::mat4 view = glm::lookAtRH(rel, rel + light.direction, anyUp(light.direction));
    v.count = 1;
    v.viewProj[0] = glm::perspectiveRH_ZO(2.0f * std::atan(tanHalf), 1.0f, zNear, zFar) * view;
    v.footprint = 2.0f * tanHalf / float(mapSize);
    return v;
  }
  // Six 90-degree faces, widened by the kernel's reach (a lookup near a face's edge keeps its taps on that face).
  const float tanHalf = 1.0f + 2.0f * float(taps + 1) / float(mapSize);
  const glm::mat4 proj = glm::perspectiveRH_ZO(2.0f * std::atan(tanHalf), 1.0f, zNear, zFar);
  const glm::vec3 axes[6] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
  v.count = 6;
  for (int f = 0; f < 6; ++f) v.viewProj[f] = proj * glm::lookAtRH(rel, rel + axes[f], anyUp(axes[f]));
  v.footprint = 2.0f * tanHalf / float(mapSize);
  return v;
}

GpuLocalLight gpuLight(const FrameLight& light, const glm::dvec3& eye, int shadowSlot) {
  GpuLocalLight g{};
  g.positionRange = glm::vec4(glm::vec3(light.position - eye), light.range);
  g.directionType = glm::vec4(light.direction, float(uint32_t(light.type)));
  g.radiance = glm::vec4(light.color * light.intensity, 0.0f);
  const float cosOuter = std::cos(light.outerConeAngle), cosInner = std::cos(light.innerConeAngle);
  g.cone = glm::vec4(cosOuter, 1.0f / std::max(cosInner - cosOuter, 1e-4f), float(shadowSlot), 0.0f);
  return g;
}

}  // namespace detail

namespace {

constexpr VkImageLayout kReadLayout = VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL;

}  // namespace

std::string Engine::Impl::createLocalLights() {
  const VkDevice dev = ctx.device;
  const VkDeviceSize align = std::max<VkDeviceSize>(ctx.properties.limits.minUniformBufferOffsetAlignment, 1);
  shadowViewStride = (sizeof(FrameUniforms) + align - 1) / align * align;
  // Per frame: one set per shadow view (frame uniforms with that view's lightViewProj) and the irradiance set.
  VkDescriptorPoolSize sizes[3] = {{VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER, (kMaxLocalShadowViews + 1) * kFramesInFlight},
                                   {VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, kFramesInFlight},
                                   {VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, 4 * kFramesInFlight}};
  VkDescriptorPoolCreateInfo pci{VK_STRUCTURE_TYPE_DESCRIPTOR_POOL_CREATE_INFO};
  pci.maxSets = (kMaxLocalShadowViews + 1) * kFramesInFlight;
  pci.poolSizeCount = 3;
  pci.pPoolSizes = sizes;
  SE_VK_TRY(vkCreateDescriptorPool(dev, &pci, nullptr, &localLightPool));
  const VkMemoryPropertyFlags host = VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT | VK_MEMORY_PROPERTY_HOST_COHERENT_BIT;
  for (FrameResources& f : frames) {
    std::string e = gpu.createBuffer(sizeof(GpuLocalLight) * kMaxPunctualLights, VK_BUFFER_USAGE_STORAGE_BUFFER_BIT,
                                     host, f.localLightBuffer);
    if (e.empty())
      e = gpu.createBuffer(sizeof(GpuLocalShadows), VK_BUFFER_USAGE_UNIFORM_BUFFER_BIT, host, f.localShadowBuffer);
    if (e.empty())
      e = gpu.createBuffer(shadowViewStride * kMaxLocalShadowViews, VK_BUFFER_USAGE_UNIFORM_BUFFER_BIT, host,
                           f.shadowViewUniforms);
    if (!e.empty()) return e;
    std::memset(f.localShadowBuffer.mapped, 0, sizeof(GpuLocalShadows));
    std::vector<VkDescriptorSetLayout> layouts(kMaxLocalShadowViews, pipelines.frameSetLayout);
    layouts.push_back(pipelines.localIrradianceSetLayout);
    std::vector<VkDescriptorSet> sets(layouts.size());
    VkDescriptorSetAllocateInfo dai{VK_STRUCTURE_TYPE_DESCRIPTOR_SET_ALLOCATE_INFO};
    dai.descriptorPool = localLightPool;
    dai.descriptorSetCount = uint32_t(layouts.size());
    dai.pSetLayouts = layouts.data();
    SE_VK_TRY(vkAllocateDescriptorSets(dev, &dai, sets.data()));
    for (uint32_t v = 0; v < kMaxLocalShadowViews; ++v) {
      f.shadowViewSets[v] = sets[v];
      VkDescriptorBufferInfo bi{f.shadowViewUniforms.buffer, v * shadowViewStride, sizeof(FrameUniforms)};
      VkWriteDescriptorSet w{VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET};
      w.dstSet = sets[v];
      w.descriptorCount = 1;
      w.descriptorType = VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER;
      w.pBufferInfo = &bi;
      vkUpdateDescriptorSets(dev, 1, &w, 0, nullptr);
    }
    f.localIrradianceSet = sets.back();
  }
  return prepareLocalShadowMaps(LocalLightSettings{.maxShadowedLights = 0});
}

void Engine::Impl::destroyLocalShadowMaps() {
  for (VkImageView v : targets.localShadowLayerViews) vkDestroyImageView(ctx.device, v, nullptr);
  targets.localShadowLayerViews.clear();
  gpu.destroy(targets.localShadowMaps);
  targets.localShadowMapSize = targets.localShadowLayers = 0;
}

void Engine::Impl::destroyLocalLights() {
  destroyLocalShadowMaps();
  for (FrameResources& f : frames)
    for (Buffer* b : {&f.localLightBuffer, &f.localShadowBuffer, &f.shadowViewUniforms}) gpu.destroy(*b);
  if (localLightPool) vkDestroyDescriptorPool(ctx.device, localLightPool, nullptr);
  localLightPool = VK_NULL_HANDLE;
}

std::string Engine::Impl::prepareLocalShadowMaps(const LocalLightSettings& settings) {
  const uint32_t shadowed = settings.enabled ? std::min(settings.maxShadowedLights, kMaxShadowedLocalLights) : 0u;
  // Without shadowed lights a 1x1 single-layer placeholder stays bound (the shaders never sample it: 0 taps).
  const uint32_t size = shadowed ? std::clamp(settings.mapSize, kMinLocalShadowMapSize, kMaxLocalShadowMapSize) : 1u;
  const uint32_t layers = shadowed ? shadowed * 6 : 1u;
  if (targets.localShadowMaps.image && size == targets.localShadowMapSize && layers == targets.localShadowLayers)
    return {};
  vkDeviceWaitIdle(ctx.device);  // frames in flight may still sample the old maps
  destroyLocalShadowMaps();
  if (std::string e = gpu.createImage({kDepthFormat,
                                       {size, size},
                                       VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT | VK_IMAGE_USAGE_SAMPLED_BIT,
                                       VK_IMAGE_ASPECT_DEPTH_BIT,
                                       1,
                                       VK_FORMAT_UNDEFINED,
                                       false,
                                       layers},
                                      targets.localShadowMaps);
      !e.empty())
    return e;
  targets.localShadowMapSize = size;
  targets.localShadowLayers = layers;
  for (uint32_t l = 0; l < layers; ++l) {
    VkImageViewCreateInfo vi{VK_STRUCTURE_TYPE_IMAGE_VIEW_CREATE_INFO};
    vi.image = targets.localShadowMaps.image;
    vi.viewType = VK_IMAGE_VIEW_TYPE_2D;
    vi.format = kDepthFormat;
    vi.subresourceRange = {VK_IMAGE_ASPECT_DEPTH_BIT, 0, 1, l, 1};
    VkImageView view = VK_NULL_HANDLE;
    SE_VK_TRY(vkCreateImageView(ctx.device, &vi, nullptr, &view));
    targets.localShadowLayerViews.push_back(view);
  }
  // Kept in SHADER_READ_ONLY_OPTIMAL between frames: the lighting set (and the probe's) bind it every frame.
  return gpu.submitNow([&](VkCommandBuffer cmd) {
    imageBarrier(cmd, targets.localShadowMaps.image, VK_IMAGE_ASPECT_DEPTH_BIT, VK_IMAGE_LAYOUT_UNDEFINED, kReadLayout,
                 VK_PIPELINE_STAGE_2_NONE, 0, VK_PIPELINE_STAGE_2_FRAGMENT_SHADER_BIT,
                 VK_ACCESS_2_SHADER_SAMPLED_READ_BIT);
  });
}

LocalLightBindings Engine::Impl::localLightBindings(const FrameResources& frame) const {
  return {targets.localShadowMaps.view, frame.localLightBuffer.buffer, frame.localLightBuffer.size,
          frame.localShadowBuffer.buffer, frame.localShadowBuffer.size};
}

void Engine::Impl::recordLocalLights(FrameResources& frame, const FrameParams& params, const FrameUniforms& uniforms,
                                     const LightingInputs& inputs) {
  VkCommandBuffer cmd = frame.cmd;
  const LocalLightSettings& settings = params.localLights;
  const glm::dvec3 eye(params.camera.eye);
  const uint32_t count = settings.enabled ? uint32_t(frameLights.size()) : 0u;
  const bool external = inputs.localLightIrradiance != VK_NULL_HANDLE;
  // An external E replaces the shadowed diffuse, so the maps are only needed for the engine's own output.
  // FrameParams::externalColor: nothing samples them.
  const bool drawMaps = count > 0 && targets.localShadowLayers >= 6 && !params.externalColor &&
                        (!external || params.outputLocalLightIrradiance);
  const uint32_t taps = std::clamp(settings.pcfKernelSize, 1u, kMaxShadowPcfKernel);
  const uint32_t mapSize = targets.localShadowMapSize;
  const std::vector<uint32_t> shadowed = drawMaps ? strongestLights(frameLights, eye, targets.localShadowLayers / 6)
                                                  : std::vector<uint32_t>{};

  GpuLocalShadows shadows{};
  shadows.counts = glm::uvec4(shadowed.empty() ? 0u : taps, uint32_t(shadowed.size()), 0u, 0u);
  // As the sun's: the offset grows by the kernel's reach ((taps - 1) / 2 texels).
  shadows.params = glm::vec4(1.0f / float(std::max(mapSize, 1u)), settings.normalOffset + 0.5f * float(taps - 1), 0.0f,
                             0.0f);
  std::vector<int> slotOf(count, -1);
  uint32_t views = 0;
  const Bounds bounds = sceneLoaded ? scene.bounds : Bounds{};
  for (uint32_t s = 0; s < shadowed.size(); ++s) {
    const LocalShadowViews v = shadowViewsFor(frameLights[shadowed[s]], bounds, eye, mapSize, taps);
    slotOf[shadowed[s]] = int(s);
    shadows.slots[s] = glm::vec4(float(6 * s), float(v.count), v.footprint, v.orthographic ? 1.0f : 0.0f);
    for (uint32_t k = 0; k < v.count; ++k) shadows.viewProj[6 * s + k] = v.viewProj[k];
    views += v.count;
  }
  auto* gpuLights = static_cast<GpuLocalLight*>(frame.localLightBuffer.mapped);
  for (uint32_t i = 0; i < count; ++i) gpuLights[i] = gpuLight(frameLights[i], eye, slotOf[i]);
  std::memcpy(frame.localShadowBuffer.mapped, &shadows, sizeof(shadows));
  localShadowStats = LocalShadowStats{count, uint32_t(shadowed.size()), views, frame.frameNumber};

  if (!shadowed.empty()) {
    // Previous frames sampled the maps (same queue): the barrier orders these writes after those reads.
    imageBarrier(cmd, targets.localShadowMaps.image, VK_IMAGE_ASPECT_DEPTH_BIT, VK_IMAGE_LAYOUT_UNDEFINED,
                 VK_IMAGE_LAYOUT_DEPTH_ATTACHMENT_OPTIMAL, VK_PIPELINE_STAGE_2_FRAGMENT_SHADER_BIT, 0,
                 VK_PIPELINE_STAGE_2_EARLY_FRAGMENT_TESTS_BIT | VK_PIPELINE_STAGE_2_LATE_FRAGMENT_TESTS_BIT,
                 VK_ACCESS_2_DEPTH_STENCIL_ATTACHMENT_READ_BIT | VK_ACCESS_2_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT);
    for (uint32_t s = 0; s < shadowed.size(); ++s) {
      const uint32_t viewCount = uint32_t(shadows.slots[s].y);
      for (uint32_t k = 0; k < viewCount; ++k) {
        const uint32_t layer = 6 * s + k;
        FrameUniforms u = uniforms;
        u.lightViewProj = shadows.viewProj[layer];  // what shadow.vert / shadow_alpha.vert project with
        std::memcpy(static_cast<char*>(frame.shadowViewUniforms.mapped) + layer * shadowViewStride, &u, sizeof(u));
        VkRenderingAttachmentInfo depth{VK_STRUCTURE_TYPE_RENDERING_ATTACHMENT_INFO};
        depth.imageView = targets.localShadowLayerViews[layer];
        depth.imageLayout = VK_IMAGE_LAYOUT_DEPTH_ATTACHMENT_OPTIMAL;
        depth.loadOp = VK_ATTACHMENT_LOAD_OP_CLEAR;
        depth.storeOp = VK_ATTACHMENT_STORE_OP_STORE;
        depth.clearValue.depthStencil = {1.0f, 0};
        beginRendering(cmd, {mapSize, mapSize}, {}, &depth);
        vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, pipelines.sceneLayout, 0, 1,
                                &frame.shadowViewSets[layer], 0, nullptr);
        vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, pipelines.shadow);
        vkCmdSetDepthBias(cmd, settings.depthBiasConstant, 0.0f, settings.depthBiasSlope);
        // Casters beyond a point or spot light's range cannot shadow anything it lights.
        const FrameLight& light = frameLights[shadowed[s]];
        const glm::vec4 reach = light.type != PunctualLight::Type::Directional && light.range > 0.0f
                                    ? glm::vec4(glm::vec3(light.position - eye), light.range)
                                    : glm::vec4(0.0f);
        if (sceneLoaded) drawScene(cmd, scene, pipelines, DrawPass::Shadow, {}, eye, ViewHandedness::Camera, reach);
        vkCmdEndRendering(cmd);
      }
    }
    imageBarrier(cmd, targets.localShadowMaps.image, VK_IMAGE_ASPECT_DEPTH_BIT,
                 VK_IMAGE_LAYOUT_DEPTH_ATTACHMENT_OPTIMAL, kReadLayout, VK_PIPELINE_STAGE_2_LATE_FRAGMENT_TESTS_BIT,
                 VK_ACCESS_2_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT, VK_PIPELINE_STAGE_2_FRAGMENT_SHADER_BIT,
                 VK_ACCESS_2_SHADER_SAMPLED_READ_BIT);
  }
  if (frame.timestamps)
    vkCmdWriteTimestamp2(cmd, VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT, frame.timestamps, kTsLocalShadowEnd);

  if (params.outputLocalLightIrradiance) {
    const VkDescriptorImageInfo images[3] = {{pipelines.nearestSampler, targets.depth.view,
                                              VK_IMAGE_LAYOUT_DEPTH_READ_ONLY_OPTIMAL},
                                             {pipelines.nearestSampler, targets.normalRoughness.view, kReadLayout},
                                             {pipelines.nearestSampler, targets.geometricNormal.view, kReadLayout}};
    for (uint32_t b = 0; b < 3; ++b) {
      VkWriteDescriptorSet w{VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET};
      w.dstSet = frame.localIrradianceSet;
      w.dstBinding = b;
      w.descriptorCount = 1;
      w.descriptorType = VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER;
      w.pImageInfo = &images[b];
      vkUpdateDescriptorSets(ctx.device, 1, &w, 0, nullptr);
    }
    writeLocalLightDescriptors(ctx.device, pipelines, frame.localIrradianceSet, kLocalIrradianceLocalLightBinding,
                               localLightBindings(frame));
    const Image& target = targets.localIrradiance;
    imageBarrier(cmd, target.image, VK_IMAGE_ASPECT_COLOR_BIT, VK_IMAGE_LAYOUT_UNDEFINED,
                 VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL, VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT, 0,
                 VK_PIPELINE_STAGE_2_COLOR_ATTACHMENT_OUTPUT_BIT, VK_ACCESS_2_COLOR_ATTACHMENT_WRITE_BIT);
    beginRendering(cmd, targets.extent, {colorAttachment(target.view, {})}, nullptr);
    vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, pipelines.localIrradiance);
    const VkDescriptorSet sets[2] = {frame.frameSet, frame.localIrradianceSet};
    vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, pipelines.localIrradianceLayout, 0, 2, sets, 0,
                            nullptr);
    vkCmdDraw(cmd, 3, 1, 0, 0);
    vkCmdEndRendering(cmd);
    imageBarrier(cmd, target.image, VK_IMAGE_ASPECT_COLOR_BIT, VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL, kReadLayout,
                 VK_PIPELINE_STAGE_2_COLOR_ATTACHMENT_OUTPUT_BIT, VK_ACCESS_2_COLOR_ATTACHMENT_WRITE_BIT,
                 VK_PIPELINE_STAGE_2_FRAGMENT_SHADER_BIT | VK_PIPELINE_STAGE_2_ALL_TRANSFER_BIT,
                 VK_ACCESS_2_SHADER_SAMPLED_READ_BIT | VK_ACCESS_2_TRANSFER_READ_BIT);
  }
  if (frame.timestamps)
    vkCmdWriteTimestamp2(cmd, VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT, frame.timestamps, kTsLocalIrradianceEnd);
}

}  // namespace sample_engine
