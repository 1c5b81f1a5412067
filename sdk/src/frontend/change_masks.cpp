#include "change_masks.h"

#include <cmath>
#include <cstring>

#include "context_impl.h"
#include "gbuffer_sampler.h"
#include "image_barriers.h"
#include "pass_constants.h"
#include "raybridge_shaders.h"

namespace rb {

int ChangeMasks::slotOf(uint32_t effect) {
  switch (effect) {
    case RB_CHANGE_SHADOWS: return 0;
    case RB_CHANGE_AO: return 1;
    case RB_CHANGE_LOCAL_LIGHTS: return 2;
    case RB_CHANGE_REFLECTIONS: return 3;
    default: return -1;
  }
}

Status ChangeMasks::prepare(Context& ctx, uint32_t masks, uint32_t width, uint32_t height) {
  if (!pipeline_.pipeline) {
    const VkShaderStageFlags cs = VK_SHADER_STAGE_COMPUTE_BIT;
    auto binding = [&](uint32_t b, VkDescriptorType t) { return VkDescriptorSetLayoutBinding{b, t, 1, cs, nullptr}; };
    const VkDescriptorType sampled = VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER;
    const VkDescriptorType storage = VK_DESCRIPTOR_TYPE_STORAGE_IMAGE;
    Result<ComputePipeline> p = ComputePipeline::create(
        ctx, SpirvModule::of(spirv::change_masks_comp),
        {binding(RB_CHANGE_BINDING_DEPTH, sampled), binding(RB_CHANGE_BINDING_REACTIVE, sampled),
         binding(RB_CHANGE_BINDING_SHADOWS, storage), binding(RB_CHANGE_BINDING_AO, storage),
         binding(RB_CHANGE_BINDING_LOCAL_LIGHTS, storage), binding(RB_CHANGE_BINDING_REFLECTIONS, storage)},
        sizeof(ChangeMaskConstants), "HybridEffects: change masks");
    if (!p) return p.error();
    pipeline_ = p.value();
  }
  if (!metricsReady_) {
    if (Status st = metrics_.init(ctx, "change masks", /*countsRays=*/false); !st) return st;
    metricsReady_ = true;
  }
  if (!sampler_) {
    Result<VkSampler> sampler = createNearestSampler(ctx);
    if (!sampler) return sampler.error();
    sampler_ = sampler.value();
  }
  if (!ring_.valid()) {
    Result<GpuBuffer> r = createBuffer(ctx, VkDeviceSize(kMaxChangeBoxes) * sizeof(GpuChangeBox) * ctx.framesInFlight(),
                                       VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | VK_BUFFER_USAGE_SHADER_DEVICE_ADDRESS_BIT,
                                       MemoryLocation::HostVisible, MemoryCategory::PassBuffers,
                                       "HybridEffects: change boxes");
    if (!r) return r.error();
    ring_ = r.value();
  }
  // One image per mask asked for, at the G-buffer's size (a new size: new images; the old ones are retired).
  for (uint32_t effect : {RB_CHANGE_SHADOWS, RB_CHANGE_AO, RB_CHANGE_LOCAL_LIGHTS, RB_CHANGE_REFLECTIONS}) {
    GpuImage& image = images_[slotOf(effect)];
    const bool wanted = (masks & effect) != 0u;
    if (image.valid() && (!wanted || image.width != width || image.height != height)) retireImage(ctx, image);
    if (!wanted || image.valid()) continue;
    Result<GpuImage> created = createStorageImage(ctx, width, height, VK_FORMAT_R8_UNORM,
                                                  VK_IMAGE_USAGE_TRANSFER_SRC_BIT, MemoryCategory::PassImages,
                                                  "HybridEffects: change mask");
    if (!created) return created.error();
    image = created.value();
  }
  return {};
}

Result<bool> ChangeMasks::record(Context& ctx, VkCommandBuffer cmd, const GBufferDesc& g, const TlasInfo& tlas,
                                 std::span<const GpuChangeBox> boxes, const ChangeMaskInputs& in) {
  written_ = 0;
  if (in.masks == 0) return false;
  // Everything exists from the first frame that could need it, so that a later change allocates nothing.
  if (Status st = prepare(ctx, in.masks, g.width, g.height); !st) return st.error();
  if (boxes.empty()) return false;
  ChangeMaskConstants pc{};
  if (Status st = fillGBufferConstants(g, tlas, ctx.frameIndex(), "HybridEffects: change masks", pc.gbuffer); !st)
    return st.error();
  const uint32_t slots = ctx.framesInFlight();
  const uint32_t count = uint32_t(std::min<size_t>(boxes.size(), kMaxChangeBoxes));
  const VkDeviceSize slotBytes = VkDeviceSize(kMaxChangeBoxes) * sizeof(GpuChangeBox);
  const VkDeviceSize offset = (ctx.frameIndex() % slots) * slotBytes;
  std::memcpy(static_cast<uint8_t*>(ring_.mapped) + offset, boxes.data(), count * sizeof(GpuChangeBox));
  const VkDeviceAddress address = ring_.address + offset;
  pc.boxes[0] = uint32_t(address);
  pc.boxes[1] = uint32_t(address >> 32);
  pc.boxCount = count;
  pc.masks = in.masks;
  const Light& l = in.shadowLight;
  pc.lightType = uint32_t(l.type);
  if (l.type == LightType::Directional) {
    float d[3] = {l.direction[0], l.direction[1], l.direction[2]};
    if (d[0] == 0.0f && d[1] == 0.0f && d[2] == 0.0f) d[1] = 1.0f;  // Light's default: the sun overhead
    const float n = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    for (int i = 0; i < 3; ++i) pc.lightDirection[i] = d[i] / n;
    pc.lightSpread = std::tan(l.angularRadiusDegrees * 3.14159265f / 180.0f);
  } else {
    for (int i = 0; i < 3; ++i) pc.lightPosition[i] = float(l.position[i] - tlas.originOffset[i]);
    pc.lightSpread = l.radius;
  }
  pc.aoRange = in.aoRange;
  pc.reactive = g.reactiveMask.view ? 1u : 0u;

  if (Status st = metrics_.beginRecording(ctx, cmd); !st) return st.error();
  metrics_.writeStart(ctx, cmd);
  const DeviceFunctions& vk = internal::deviceFunctions(ctx);
  const VkPipelineStageFlags readers = VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT |
                                       VK_PIPELINE_STAGE_RAY_TRACING_SHADER_BIT_KHR;
  // Last frame's readers are done before the masks are rewritten (every pixel: the old contents are dropped).
  VkImageMemoryBarrier toWrite[4];
  uint32_t n = 0;
  for (const GpuImage& image : images_)
    if (image.valid())
      toWrite[n++] = colorImageBarrier(image.image, VK_IMAGE_LAYOUT_UNDEFINED, VK_IMAGE_LAYOUT_GENERAL, 0,
                                       VK_ACCESS_SHADER_WRITE_BIT);
  vk.vkCmdPipelineBarrier(cmd, readers, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, 0, 0, nullptr, 0, nullptr, n, toWrite);

  const GpuImage* any = nullptr;
  for (const GpuImage& image : images_)
    if (image.valid()) any = &image;
  DescriptorWrites w;
  const VkSampler sampler = sampler_;
  w.sampledImage(RB_CHANGE_BINDING_DEPTH, g.depth.view, sampler, readLayout(g.depth));
  const GBufferImage& reactive = g.reactiveMask.view ? g.reactiveMask : g.depth;
  w.sampledImage(RB_CHANGE_BINDING_REACTIVE, reactive.view, sampler, readLayout(reactive));
  for (uint32_t effect : {RB_CHANGE_SHADOWS, RB_CHANGE_AO, RB_CHANGE_LOCAL_LIGHTS, RB_CHANGE_REFLECTIONS}) {
    const GpuImage& image = images_[slotOf(effect)].valid() ? images_[slotOf(effect)] : *any;
    w.storageImage(RB_CHANGE_BINDING_SHADOWS + uint32_t(slotOf(effect)), image.view);
  }
  pipeline_.dispatch(ctx, cmd, w.writes, &pc, sizeof pc, g.width, g.height);

  VkImageMemoryBarrier toRead[4];
  n = 0;
  for (const GpuImage& image : images_)
    if (image.valid())
      toRead[n++] = colorImageBarrier(image.image, VK_IMAGE_LAYOUT_GENERAL, VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL,
                                      VK_ACCESS_SHADER_WRITE_BIT, VK_ACCESS_SHADER_READ_BIT);
  vk.vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, readers, 0, 0, nullptr, 0, nullptr, n, toRead);
  metrics_.writeEnd(ctx, cmd);
  written_ = in.masks;
  return true;
}

GBufferDesc ChangeMasks::gbufferFor(const GBufferDesc& g, uint32_t effect) const {
  const GpuImage* image = mask(effect);
  if (!image) return g;
  GBufferDesc out = g;
  out.reactiveMask = {};
  out.reactiveMask.view = image->view;
  out.reactiveMask.layout = VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL;
  out.reactiveMask.format = VK_FORMAT_R8_UNORM;
  out.reactiveMask.width = image->width;
  out.reactiveMask.height = image->height;
  return out;
}

const GpuImage* ChangeMasks::mask(uint32_t effect) const {
  const int slot = slotOf(effect);
  if (slot < 0 || (written_ & effect) == 0u || !images_[slot].valid()) return nullptr;
  return &images_[slot];
}

void ChangeMasks::retire(Context& ctx) {
  for (GpuImage& image : images_)
    if (image.valid()) retireImage(ctx, image);
  if (ring_.valid()) retireBuffer(ctx, ring_);
  if (pipeline_.pipeline) pipeline_.retire(ctx);
  if (metricsReady_) metrics_.retire(ctx);
  metricsReady_ = false;
  if (sampler_) {
    Context* context = &ctx;
    VkSampler sampler = sampler_;
    internal::contextImpl(ctx).retire([context, sampler]() mutable { destroySampler(*context, sampler); });
    sampler_ = VK_NULL_HANDLE;
  }
  written_ = 0;
}

}  // namespace rb
