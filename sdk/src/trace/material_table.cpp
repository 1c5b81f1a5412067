// MaterialTable: the engine's materials in a GPU buffer and its textures in one bindless descriptor set.
#include <raybridge/material_table.h>

#include <algorithm>
#include <cstring>
#include <string>

#include "context_impl.h"
#include "material_table_impl.h"
#include "raybridge_shader_interface.glsl"

namespace rb {

static_assert(RB_ALPHA_OPAQUE == uint32_t(AlphaMode::Opaque));
static_assert(RB_ALPHA_MASK == uint32_t(AlphaMode::Mask));
static_assert(RB_ALPHA_BLEND == uint32_t(AlphaMode::Blend));

Result<VkDescriptorSetLayout> createTextureSetLayout(Context& ctx) {
  Context::Impl& c = internal::contextImpl(ctx);
  // Partially bound with a variable count, so a table of any size up to kMaxMaterialTextures (none included)
  // fits one layout.
  VkDescriptorSetLayoutBinding textures{0, VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, kMaxMaterialTextures,
                                        kMaterialStages, nullptr};
  VkDescriptorBindingFlags flags = VK_DESCRIPTOR_BINDING_PARTIALLY_BOUND_BIT |
                                   VK_DESCRIPTOR_BINDING_VARIABLE_DESCRIPTOR_COUNT_BIT;
  VkDescriptorSetLayoutBindingFlagsCreateInfo flagsInfo{
      VK_STRUCTURE_TYPE_DESCRIPTOR_SET_LAYOUT_BINDING_FLAGS_CREATE_INFO};
  flagsInfo.bindingCount = 1;
  flagsInfo.pBindingFlags = &flags;
  VkDescriptorSetLayoutCreateInfo sl{VK_STRUCTURE_TYPE_DESCRIPTOR_SET_LAYOUT_CREATE_INFO, &flagsInfo};
  sl.bindingCount = 1;
  sl.pBindings = &textures;
  VkDescriptorSetLayout layout = VK_NULL_HANDLE;
  VkResult r = c.vk.vkCreateDescriptorSetLayout(c.desc.device, &sl, c.allocator(), &layout);
  if (r != VK_SUCCESS) return vulkanError(r, "vkCreateDescriptorSetLayout (material textures)");
  return layout;
}

MaterialTable::Impl::~Impl() {  // frames in flight may still read the buffer and the texture set
  Context::Impl& c = internal::contextImpl(ctx);
  retireBuffer(ctx, materials);
  c.retireHandle(pool, &DeviceFunctions::vkDestroyDescriptorPool);
  c.retireHandle(textureLayout, &DeviceFunctions::vkDestroyDescriptorSetLayout);
  c.retireHandle(textureSampler, &DeviceFunctions::vkDestroySampler);
}

MaterialTable::MaterialTable(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
MaterialTable::~MaterialTable() = default;

Result<std::unique_ptr<MaterialTable>> MaterialTable::create(Context& context) {
  Context::Impl& c = internal::contextImpl(context);
  auto impl = std::make_unique<Impl>(context);
  Result<VkDescriptorSetLayout> layout = createTextureSetLayout(context);
  if (!layout) return layout.error();
  impl->textureLayout = layout.value();
  VkSamplerCreateInfo si{VK_STRUCTURE_TYPE_SAMPLER_CREATE_INFO};
  si.magFilter = si.minFilter = VK_FILTER_LINEAR;
  si.mipmapMode = VK_SAMPLER_MIPMAP_MODE_LINEAR;
  si.addressModeU = si.addressModeV = si.addressModeW = VK_SAMPLER_ADDRESS_MODE_REPEAT;
  si.maxLod = VK_LOD_CLAMP_NONE;
  VkSampler sampler = VK_NULL_HANDLE;  // not the member: a failed create leaves its output undefined
  VkResult r = c.vk.vkCreateSampler(c.desc.device, &si, c.allocator(), &sampler);
  if (r != VK_SUCCESS) return vulkanError(r, "vkCreateSampler (material textures)");
  impl->textureSampler = sampler;
  std::unique_ptr<MaterialTable> table(new MaterialTable(std::move(impl)));
  Material defaultMaterial;
  if (Status s = table->setMaterials(std::span(&defaultMaterial, 1), {}); !s) return s.error();
  return table;
}

uint32_t MaterialTable::materialCount() const { return impl_->materialCount; }

MaterialTableInfo MaterialTable::info() const {
  const Impl& s = *impl_;
  return {s.materials.buffer, s.materials.size, s.textureSet, s.materialCount};
}

Status MaterialTable::setMaterials(std::span<const Material> materials, std::span<const VkImageView> textures) {
  Impl& s = *impl_;
  Context::Impl& c = internal::contextImpl(s.ctx);
  auto invalid = [](const std::string& m) {
    return Error{ErrorCode::InvalidArgument, VK_SUCCESS, "MaterialTable::setMaterials: " + m};
  };
  if (materials.empty()) return invalid("at least one material is needed (instances index the table)");
  if (textures.size() > kMaxMaterialTextures) {
    return invalid(std::to_string(textures.size()) + " textures exceed the limit of " +
                   std::to_string(kMaxMaterialTextures));
  }
  for (size_t i = 0; i < materials.size(); ++i) {
    const Material& m = materials[i];
    const std::string name = "materials[" + std::to_string(i) + "]";
    for (uint32_t t : {m.baseColorTexture, m.metallicRoughnessTexture, m.emissiveTexture}) {
      if (t != kNoTexture && t >= textures.size()) {
        return invalid(name + " uses texture " + std::to_string(t) + " but only " + std::to_string(textures.size()) +
                       " textures were given");
      }
    }
    if (m.alphaMode != AlphaMode::Opaque && m.alphaMode != AlphaMode::Mask && m.alphaMode != AlphaMode::Blend) {
      return invalid(name + ".alphaMode " + std::to_string(uint32_t(m.alphaMode)) + " is not an AlphaMode");
    }
    if (!(m.alphaCutoff >= 0.0f && m.alphaCutoff <= 1.0f)) {
      return invalid(name + ".alphaCutoff " + std::to_string(m.alphaCutoff) + " is outside [0, 1]");
    }
    if (m.texcoordSet != 0) {
      return invalid(name + ".texcoordSet " + std::to_string(m.texcoordSet) +
                     ": only set 0 (MeshDesc::texcoordAddress) is read");
    }
  }
  for (size_t i = 0; i < textures.size(); ++i) {
    if (!textures[i]) return invalid("textures[" + std::to_string(i) + "] is VK_NULL_HANDLE");
  }
  Result<GpuBuffer> buffer = createBuffer(s.ctx, materials.size() * sizeof(GpuMaterial),
                                          VK_BUFFER_USAGE_STORAGE_BUFFER_BIT, MemoryLocation::HostVisibleDeviceLocal,
                                          MemoryCategory::PassBuffers, "material table");
  if (!buffer) return buffer.error();
  auto* out = static_cast<GpuMaterial*>(buffer->mapped);
  for (size_t i = 0; i < materials.size(); ++i) {
    const Material& m = materials[i];
    GpuMaterial g{};
    std::memcpy(g.baseColor, m.baseColor, sizeof g.baseColor);
    g.metallic = m.metallic;
    g.roughness = m.roughness;
    g.baseColorTexture = m.baseColorTexture;
    g.metallicRoughnessTexture = m.metallicRoughnessTexture;
    std::memcpy(g.emissive, m.emissive, sizeof m.emissive);
    g.emissiveTexture = m.emissiveTexture;
    const bool identity = std::all_of(std::begin(m.textureTransform), std::end(m.textureTransform),
                                      [](float v) { return v == 0.0f; });
    const float t[6] = {1.0f, 0.0f, 0.0f, 0.0f, 1.0f, 0.0f};
    const float* transform = identity ? t : m.textureTransform;
    std::memcpy(g.uvTransformRow0, transform, 3 * sizeof(float));
    std::memcpy(g.uvTransformRow1, transform + 3, 3 * sizeof(float));
    g.alphaMode = static_cast<uint32_t>(m.alphaMode);
    g.alphaCutoff = m.alphaCutoff == 0.0f ? kDefaultAlphaCutoff : m.alphaCutoff;
    out[i] = g;
  }
  const uint32_t count = static_cast<uint32_t>(textures.size());
  VkDescriptorPoolSize size{VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, std::max(count, 1u)};
  VkDescriptorPoolCreateInfo pi{VK_STRUCTURE_TYPE_DESCRIPTOR_POOL_CREATE_INFO};
  pi.maxSets = 1;
  pi.poolSizeCount = 1;
  pi.pPoolSizes = &size;
  VkDescriptorPool pool = VK_NULL_HANDLE;
  VkResult r = c.vk.vkCreateDescriptorPool(c.desc.device, &pi, c.allocator(), &pool);
  if (r != VK_SUCCESS) {
    destroyBuffer(s.ctx, buffer.value());
    return vulkanError(r, "vkCreateDescriptorPool (material textures)");
  }
  VkDescriptorSetVariableDescriptorCountAllocateInfo variable{
      VK_STRUCTURE_TYPE_DESCRIPTOR_SET_VARIABLE_DESCRIPTOR_COUNT_ALLOCATE_INFO};
  variable.descriptorSetCount = 1;
  variable.pDescriptorCounts = &count;
  VkDescriptorSetAllocateInfo ai{VK_STRUCTURE_TYPE_DESCRIPTOR_SET_ALLOCATE_INFO, &variable};
  ai.descriptorPool = pool;
  ai.descriptorSetCount = 1;
  ai.pSetLayouts = &s.textureLayout;
  VkDescriptorSet set = VK_NULL_HANDLE;
  r = c.vk.vkAllocateDescriptorSets(c.desc.device, &ai, &set);
  if (r != VK_SUCCESS) {
    c.vk.vkDestroyDescriptorPool(c.desc.device, pool, c.allocator());
    destroyBuffer(s.ctx, buffer.value());
    return vulkanError(r, "vkAllocateDescriptorSets (material textures)");
  }
  if (count) {
    std::vector<VkDescriptorImageInfo> infos(count);
    for (uint32_t i = 0; i < count; ++i) {
      infos[i] = {s.textureSampler, textures[i], VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL};
    }
    VkWriteDescriptorSet w{VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET};
    w.dstSet = set;
    w.dstBinding = 0;
    w.descriptorCount = count;
    w.descriptorType = VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER;
    w.pImageInfo = infos.data();
    c.vk.vkUpdateDescriptorSets(c.desc.device, 1, &w, 0, nullptr);
  }
  // The previous table may be in use by frames in flight.
  retireBuffer(s.ctx, s.materials);
  c.retireHandle(s.pool, &DeviceFunctions::vkDestroyDescriptorPool);
  s.materials = buffer.value();
  s.pool = pool;
  s.textureSet = set;
  s.materialCount = static_cast<uint32_t>(materials.size());
  return {};
}

}  // namespace rb
