#include "reflection_probe.h"

#include <algorithm>
#include <bit>
#include <cstring>

#include "render_utils.h"
#include "vk_check.h"

namespace sample_engine::detail {
namespace {

// Per face, the world axes that become (sc, tc, ma) in Vulkan's cube-map face selection table ("Cube Map
// Face Selection and Transformations"): face texel (s, t) = ((sc/|ma| + 1) / 2, (tc/|ma| + 1) / 2), t = 0 on
// the first row. Rendering each face with clip = (sc, tc, depth(ma), ma) puts every direction exactly on the
// texel a lookup along it reads, without any flip bookkeeping.
constexpr float kFaceAxes[6][3][3] = {
    {{0, 0, -1}, {0, -1, 0}, {1, 0, 0}},   // +X
    {{0, 0, 1}, {0, -1, 0}, {-1, 0, 0}},   // -X
    {{1, 0, 0}, {0, 0, 1}, {0, 1, 0}},     // +Y
    {{1, 0, 0}, {0, 0, -1}, {0, -1, 0}},   // -Y
    {{1, 0, 0}, {0, -1, 0}, {0, 0, 1}},    // +Z
    {{-1, 0, 0}, {0, -1, 0}, {0, 0, -1}},  // -Z
};

// Rotation only: the capture's positions are relative to the probe (drawScene rebases to it).
glm::mat4 faceView(uint32_t face) {
  glm::mat4 v(1.0f);
  for (int row = 0; row < 3; ++row)
    for (int col = 0; col < 3; ++col) v[col][row] = kFaceAxes[face][row][col];
  return v;
}

// x, y pass through; depth = A + B / ma maps [zNear, zFar] to [0, 1] (standard Z, like the main camera).
glm::mat4 faceProjection(float zNear, float zFar) {
  glm::mat4 p(0.0f);
  p[0][0] = 1.0f;
  p[1][1] = 1.0f;
  p[2][2] = zFar / (zFar - zNear);
  p[3][2] = zFar * zNear / (zNear - zFar);
  p[2][3] = 1.0f;
  return p;
}

}  // namespace

uint32_t ReflectionProbe::clampResolution(uint32_t resolution) { return std::clamp(resolution, 8u, 512u); }

glm::vec3 ReflectionProbe::positionFor(const ReflectionProbeSettings& settings, const Bounds& bounds) {
  if (settings.position) return *settings.position;
  if (!bounds.valid()) return {0.0f, settings.heightAboveGround, 0.0f};
  glm::vec3 p = bounds.center();
  p.y = std::max(p.y, bounds.min.y + settings.heightAboveGround);
  return p;
}

std::string ReflectionProbe::create(Gpu& gpu, const VulkanContext& ctx, const Pipelines& pipelines) {
  gpu_ = &gpu;
  pipelines_ = &pipelines;
  device_ = ctx.device;
  const VkDeviceSize align = std::max<VkDeviceSize>(ctx.properties.limits.minUniformBufferOffsetAlignment, 1);
  uniformStride_ = (sizeof(FrameUniforms) + align - 1) / align * align;

  VkDescriptorPoolSize sizes[3] = {{VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER, 7 * kFramesInFlight},
                                   {VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, kLightingSetSamplers * kFramesInFlight},
                                   {VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, kFramesInFlight}};
  VkDescriptorPoolCreateInfo pci{VK_STRUCTURE_TYPE_DESCRIPTOR_POOL_CREATE_INFO};
  pci.maxSets = 7 * kFramesInFlight;
  pci.poolSizeCount = 3;
  pci.pPoolSizes = sizes;
  SE_VK_TRY(vkCreateDescriptorPool(device_, &pci, nullptr, &pool_));
  for (SlotResources& slot : slots_) {
    if (std::string e = gpu.createBuffer(6 * uniformStride_, VK_BUFFER_USAGE_UNIFORM_BUFFER_BIT,
                                         VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT | VK_MEMORY_PROPERTY_HOST_COHERENT_BIT,
                                         slot.uniforms);
        !e.empty())
      return e;
    VkDescriptorSetLayout layouts[7];
    std::fill(layouts, layouts + 6, pipelines.frameSetLayout);
    layouts[6] = pipelines.lightingSetLayout;
    VkDescriptorSet sets[7];
    VkDescriptorSetAllocateInfo dai{VK_STRUCTURE_TYPE_DESCRIPTOR_SET_ALLOCATE_INFO};
    dai.descriptorPool = pool_;
    dai.descriptorSetCount = 7;
    dai.pSetLayouts = layouts;
    SE_VK_TRY(vkAllocateDescriptorSets(device_, &dai, sets));
    std::copy(sets, sets + 6, slot.faceSets.begin());
    slot.lightingSet = sets[6];
    for (uint32_t f = 0; f < 6; ++f) {
      VkDescriptorBufferInfo bi{slot.uniforms.buffer, f * uniformStride_, sizeof(FrameUniforms)};
      VkWriteDescriptorSet w{VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET};
      w.dstSet = slot.faceSets[f];
      w.descriptorCount = 1;
      w.descriptorType = VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER;
      w.pBufferInfo = &bi;
      vkUpdateDescriptorSets(device_, 1, &w, 0, nullptr);
    }
  }

  if (std::string e = gpu.createImage({VK_FORMAT_R8G8B8A8_UNORM,
                                       {1, 1},
                                       VK_IMAGE_USAGE_SAMPLED_BIT | VK_IMAGE_USAGE_TRANSFER_DST_BIT,
                                       VK_IMAGE_ASPECT_COLOR_BIT,
                                       1,
                                       VK_FORMAT_UNDEFINED,
                                       true},
                                      fallback_);
      !e.empty())
    return e;
  return gpu.submitNow([&](VkCommandBuffer cmd) {
    imageBarrier(cmd, fallback_.image, VK_IMAGE_ASPECT_COLOR_BIT, VK_IMAGE_LAYOUT_UNDEFINED,
                 VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, VK_PIPELINE_STAGE_2_NONE, 0, VK_PIPELINE_STAGE_2_CLEAR_BIT,
                 VK_ACCESS_2_TRANSFER_WRITE_BIT);
    VkClearColorValue black{};
    VkImageSubresourceRange range{VK_IMAGE_ASPECT_COLOR_BIT, 0, 1, 0, 6};
    vkCmdClearColorImage(cmd, fallback_.image, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, &black, 1, &range);
    imageBarrier(cmd, fallback_.image, VK_IMAGE_ASPECT_COLOR_BIT, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL,
                 VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL, VK_PIPELINE_STAGE_2_CLEAR_BIT,
                 VK_ACCESS_2_TRANSFER_WRITE_BIT, VK_PIPELINE_STAGE_2_FRAGMENT_SHADER_BIT,
                 VK_ACCESS_2_SHADER_SAMPLED_READ_BIT);
  });
}

void ReflectionProbe::destroyCube() {
  for (VkImageView& v : faceViews_) {
    if (v) vkDestroyImageView(device_, v, nullptr);
    v = VK_NULL_HANDLE;
  }
  gpu_->destroy(cube_);
  gpu_->destroy(depth_);
  captured_ = false;
}

void ReflectionProbe::destroy(Gpu& gpu) {
  if (!gpu_) return;
  destroyCube();
  gpu.destroy(fallback_);
  for (SlotResources& slot : slots_) gpu.destroy(slot.uniforms);
  if (pool_) vkDestroyDescriptorPool(device_, pool_, nullptr);  // frees the sets
  pool_ = VK_NULL_HANDLE;
  gpu_ = nullptr;
}

std::string ReflectionProbe::prepare(uint32_t resolution) {
  if (cube_.image && cube_.extent.width == resolution) return {};
  if (cube_.image) vkDeviceWaitIdle(device_);
  destroyCube();
  const uint32_t mips = uint32_t(std::bit_width(resolution));  // down to 1x1
  std::string e = gpu_->createImage({kHdrFormat,
                                     {resolution, resolution},
                                     VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT | VK_IMAGE_USAGE_SAMPLED_BIT |
                                         VK_IMAGE_USAGE_TRANSFER_SRC_BIT | VK_IMAGE_USAGE_TRANSFER_DST_BIT,
                                     VK_IMAGE_ASPECT_COLOR_BIT,
                                     mips,
                                     VK_FORMAT_UNDEFINED,
                                     true},
                                    cube_);
  if (e.empty())
    e = gpu_->createImage({kDepthFormat,
                           {resolution, resolution},
                           VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT,
                           VK_IMAGE_ASPECT_DEPTH_BIT},
                          depth_);
  for (uint32_t f = 0; f < 6 && e.empty(); ++f) {
    VkImageViewCreateInfo vi{VK_STRUCTURE_TYPE_IMAGE_VIEW_CREATE_INFO};
    vi.image = cube_.image;
    vi.viewType = VK_IMAGE_VIEW_TYPE_2D;
    vi.format = kHdrFormat;
    vi.subresourceRange = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 1, f, 1};
    VkResult r = vkCreateImageView(device_, &vi, nullptr, &faceViews_[f]);
    if (r != VK_SUCCESS) e = vkFailure("vkCreateImageView", r);
  }
  if (!e.empty()) destroyCube();
  return e;
}

void ReflectionProbe::recordCapture(VkCommandBuffer cmd, uint32_t slot, const FrameUniforms& base, const ProbeKey& key,
                                    const GpuScene* scene, VkImageView shadowMap, const DefaultImages& defaults,
                                    const LocalLightBindings& localLights) {
  const Pipelines& p = *pipelines_;
  SlotResources& res = slots_[slot];
  const uint32_t size = cube_.extent.width;
  const VkExtent2D extent{size, size};

  // Near/far from the scene size: every point of the bounds lies within (distance to centre + radius).
  const bool bounded = scene && scene->bounds.valid();
  const float radius = bounded ? std::max(scene->bounds.radius(), 1e-3f) : 1.0f;
  const float reach = radius + (bounded ? glm::length(key.position - scene->bounds.center()) : 0.0f);
  const float zNear = radius * 1e-3f, zFar = reach * 1.5f;
  const glm::mat4 proj = faceProjection(zNear, zFar);
  for (uint32_t f = 0; f < 6; ++f) {
    FrameUniforms u = base;
    u.view = faceView(f);
    u.proj = proj;
    u.viewProj = proj * u.view;
    u.invViewProj = glm::inverse(u.viewProj);
    u.invProj = glm::inverse(proj);
    u.lightViewProj = key.lightViewProj;  // the same shadow-map texels as the camera's, probe-relative
    u.cameraPos = glm::vec4(key.position, 1.0f);
    u.viewport = glm::vec4(float(size), float(size), 1.0f / float(size), 1.0f / float(size));
    u.inputs = glm::uvec4(0u);       // own shadow map, no AO, constant-sky reflections
    u.probe = glm::vec4(0.0f);       // never samples itself
    u.localLights = glm::uvec4(0u);  // no KHR lights (a known limitation: their buffer is camera-relative)
    std::memcpy(static_cast<char*>(res.uniforms.mapped) + f * uniformStride_, &u, sizeof(u));
  }
  writeImageDescriptors(device_, res.lightingSet,
                        {{p.shadowSampler, shadowMap, VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL},
                         {p.screenSampler, defaults.white.view, VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL},
                         {p.screenSampler, defaults.white.view, VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL},
                         {p.screenSampler, defaults.black.view, VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL},
                         {p.cubeSampler, fallback_.view, VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL}});
  writeLocalLightDescriptors(device_, p, res.lightingSet, kLightingLocalLightBinding, localLights);
  writeImageDescriptors(device_, res.lightingSet,
                        {{p.screenSampler, defaults.black.view, VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL}}, 8);

  // Earlier frames may still sample the cube (same queue, so the barrier's source scope covers them).
  imageBarrier(cmd, cube_.image, VK_IMAGE_ASPECT_COLOR_BIT, VK_IMAGE_LAYOUT_UNDEFINED,
               VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL, VK_PIPELINE_STAGE_2_FRAGMENT_SHADER_BIT, 0,
               VK_PIPELINE_STAGE_2_COLOR_ATTACHMENT_OUTPUT_BIT, VK_ACCESS_2_COLOR_ATTACHMENT_WRITE_BIT, 0, 1);
  if (cube_.mipLevels > 1)
    imageBarrier(cmd, cube_.image, VK_IMAGE_ASPECT_COLOR_BIT, VK_IMAGE_LAYOUT_UNDEFINED,
                 VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, VK_PIPELINE_STAGE_2_FRAGMENT_SHADER_BIT, 0,
                 VK_PIPELINE_STAGE_2_BLIT_BIT, VK_ACCESS_2_TRANSFER_WRITE_BIT, 1, cube_.mipLevels - 1);
  // The ambient radiance, not the displayed sky color: a face that sees only sky then reproduces the
  // constant-sky fallback exactly.
  const glm::vec3 background = glm::vec3(base.sky) * base.sky.w;
  const VkClearColorValue clear{{background.r, background.g, background.b, 1.0f}};
  for (uint32_t f = 0; f < 6; ++f) {
    // Each face clears and rewrites the shared depth image: order it after the previous face's tests.
    imageBarrier(cmd, depth_.image, VK_IMAGE_ASPECT_DEPTH_BIT, VK_IMAGE_LAYOUT_UNDEFINED,
                 VK_IMAGE_LAYOUT_DEPTH_ATTACHMENT_OPTIMAL,
                 VK_PIPELINE_STAGE_2_EARLY_FRAGMENT_TESTS_BIT | VK_PIPELINE_STAGE_2_LATE_FRAGMENT_TESTS_BIT,
                 VK_ACCESS_2_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT,
                 VK_PIPELINE_STAGE_2_EARLY_FRAGMENT_TESTS_BIT | VK_PIPELINE_STAGE_2_LATE_FRAGMENT_TESTS_BIT,
                 VK_ACCESS_2_DEPTH_STENCIL_ATTACHMENT_READ_BIT | VK_ACCESS_2_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT);
    VkRenderingAttachmentInfo depth{VK_STRUCTURE_TYPE_RENDERING_ATTACHMENT_INFO};
    depth.imageView = depth_.view;
    depth.imageLayout = VK_IMAGE_LAYOUT_DEPTH_ATTACHMENT_OPTIMAL;
    depth.loadOp = VK_ATTACHMENT_LOAD_OP_CLEAR;
    depth.storeOp = VK_ATTACHMENT_STORE_OP_DONT_CARE;
    depth.clearValue.depthStencil = {1.0f, 0};
    beginRendering(cmd, extent, {colorAttachment(faceViews_[f], clear)}, &depth);
    vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, p.sceneLayout, 0, 1, &res.faceSets[f], 0, nullptr);
    vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, p.sceneLayout, 2, 1, &res.lightingSet, 0, nullptr);
    if (scene) {
      // The faces are mirror images (see kFaceAxes): front faces wind the other way.
      const glm::dvec3 origin(key.position);
      drawScene(cmd, *scene, p, DrawPass::Lighting, {p.probeCapture, p.probeCaptureMasked}, origin,
                ViewHandedness::MirroredCubeFace);
      drawBlended(cmd, *scene, p, origin, ViewHandedness::MirroredCubeFace);
    }
    vkCmdEndRendering(cmd);
  }

  // Mip chain by successive 2x box blits of all six faces: roughness picks the mip in the lighting pass.
  imageBarrier(cmd, cube_.image, VK_IMAGE_ASPECT_COLOR_BIT, VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL,
               VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, VK_PIPELINE_STAGE_2_COLOR_ATTACHMENT_OUTPUT_BIT,
               VK_ACCESS_2_COLOR_ATTACHMENT_WRITE_BIT, VK_PIPELINE_STAGE_2_BLIT_BIT, VK_ACCESS_2_TRANSFER_READ_BIT, 0,
               1);
  for (uint32_t level = 1; level < cube_.mipLevels; ++level) {
    const int32_t src = int32_t(std::max(size >> (level - 1), 1u)), dst = int32_t(std::max(size >> level, 1u));
    VkImageBlit blit{};
    blit.srcSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, level - 1, 0, 6};
    blit.srcOffsets[1] = {src, src, 1};
    blit.dstSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, level, 0, 6};
    blit.dstOffsets[1] = {dst, dst, 1};
    vkCmdBlitImage(cmd, cube_.image, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, cube_.image,
                   VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, 1, &blit, VK_FILTER_LINEAR);
    imageBarrier(cmd, cube_.image, VK_IMAGE_ASPECT_COLOR_BIT, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL,
                 VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, VK_PIPELINE_STAGE_2_BLIT_BIT, VK_ACCESS_2_TRANSFER_WRITE_BIT,
                 VK_PIPELINE_STAGE_2_BLIT_BIT, VK_ACCESS_2_TRANSFER_READ_BIT, level, 1);
  }
  imageBarrier(cmd, cube_.image, VK_IMAGE_ASPECT_COLOR_BIT, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL,
               VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL, VK_PIPELINE_STAGE_2_BLIT_BIT, VK_ACCESS_2_TRANSFER_WRITE_BIT,
               VK_PIPELINE_STAGE_2_FRAGMENT_SHADER_BIT, VK_ACCESS_2_SHADER_SAMPLED_READ_BIT);
  captured_ = true;
  key_ = key;
}

}  // namespace sample_engine::detail
