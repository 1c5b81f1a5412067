#include "gbuffer_sampler.h"

#include "context_impl.h"

namespace rb {

Result<VkSampler> createNearestSampler(Context& ctx) {
  Context::Impl& c = internal::contextImpl(ctx);
  VkSamplerCreateInfo info{VK_STRUCTURE_TYPE_SAMPLER_CREATE_INFO};
  info.magFilter = info.minFilter = VK_FILTER_NEAREST;
  info.mipmapMode = VK_SAMPLER_MIPMAP_MODE_NEAREST;
  info.addressModeU = info.addressModeV = info.addressModeW = VK_SAMPLER_ADDRESS_MODE_CLAMP_TO_EDGE;
  info.maxLod = 0.0f;
  VkSampler sampler = VK_NULL_HANDLE;
  VkResult r = c.vk.vkCreateSampler(c.desc.device, &info, c.allocator(), &sampler);
  if (r != VK_SUCCESS) return vulkanError(r, "vkCreateSampler");
  return sampler;
}

void destroySampler(Context& ctx, VkSampler& sampler) {
  if (sampler) {
    internal::deviceFunctions(ctx).vkDestroySampler(ctx.device(), sampler, internal::contextImpl(ctx).allocator());
  }
  sampler = VK_NULL_HANDLE;
}

}  // namespace rb
