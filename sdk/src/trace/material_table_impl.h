// A MaterialTable's state: the GPU material buffer and the bindless texture set (passes read them through the
// public MaterialTable::info()), and the set layout every pass's pipeline declares for it (identically defined
// layouts are compatible).
#pragma once

#include <raybridge/material_table.h>

#include "gpu_memory.h"

namespace rb {

// Mirrors GpuMaterial in shaders/shading_records.glsl (std430). Defaults are resolved on the host.
struct GpuMaterial {
  float baseColor[4];
  float metallic, roughness;
  uint32_t baseColorTexture, metallicRoughnessTexture;
  float emissive[3];
  uint32_t emissiveTexture;
  float uvTransformRow0[3];
  uint32_t alphaMode;  // RB_ALPHA_*
  float uvTransformRow1[3];
  float alphaCutoff;
};
static_assert(sizeof(GpuMaterial) == 80, "must match shaders/shading_records.glsl");

// The stages that read the texture set: reflection hits shade with it, any-hit shaders alpha-test with it.
inline constexpr VkShaderStageFlags kMaterialStages = VK_SHADER_STAGE_CLOSEST_HIT_BIT_KHR |
                                                      VK_SHADER_STAGE_ANY_HIT_BIT_KHR;

// The layout of set RB_SET_TEXTURES; the caller owns it (retire with vkDestroyDescriptorSetLayout).
Result<VkDescriptorSetLayout> createTextureSetLayout(Context& ctx);

struct MaterialTable::Impl {
  Context& ctx;
  VkDescriptorSetLayout textureLayout = VK_NULL_HANDLE;
  VkSampler textureSampler = VK_NULL_HANDLE;
  // The current table: its buffer, and the texture set with the pool it came from.
  GpuBuffer materials;
  VkDescriptorPool pool = VK_NULL_HANDLE;
  VkDescriptorSet textureSet = VK_NULL_HANDLE;
  uint32_t materialCount = 0;
  explicit Impl(Context& c) : ctx(c) {}
  ~Impl();
};

}  // namespace rb
