#include <raybridge/reflection_pass.h>

#include <cmath>
#include <cstring>
#include <string>

#include "context_impl.h"
#include "pass_core.h"
#include "raybridge_shaders.h"

namespace rb {

namespace {

constexpr uint32_t kMaxTextures = 4096;

// Mirrors GpuMaterial in shaders/reflection_common.glsl.
struct GpuMaterial {
  float baseColor[4];
  float metallic, roughness;
  uint32_t baseColorTexture, metallicRoughnessTexture;
  float emissive[3];
  uint32_t emissiveTexture;
};
static_assert(sizeof(GpuMaterial) == 48, "must match shaders/reflection_common.glsl");

}  // namespace

struct ReflectionPass::Impl {
  Context& ctx;
  PassCore core;
  VkDescriptorSetLayout textureLayout = VK_NULL_HANDLE;
  VkSampler textureSampler = VK_NULL_HANDLE;
  // The current material table: its buffer, and the texture set with the pool it came from.
  GpuBuffer materials;
  VkDescriptorPool pool = VK_NULL_HANDLE;
  VkDescriptorSet textureSet = VK_NULL_HANDLE;
  uint32_t materialCount = 0;
  ReflectionOutputs outputs;
  explicit Impl(Context& c) : ctx(c) {}
  ~Impl() {  // frames in flight may still trace with it and read its material table and texture set
    Context::Impl& c = internal::contextImpl(ctx);
    core.retire(ctx);
    retireBuffer(ctx, materials);
    c.retireHandle(pool, &DeviceFunctions::vkDestroyDescriptorPool);
    c.retireHandle(textureLayout, &DeviceFunctions::vkDestroyDescriptorSetLayout);
    c.retireHandle(textureSampler, &DeviceFunctions::vkDestroySampler);
  }
};

ReflectionPass::ReflectionPass(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
ReflectionPass::~ReflectionPass() = default;

Result<std::unique_ptr<ReflectionPass>> ReflectionPass::create(Context& context) {
  Context::Impl& c = internal::contextImpl(context);
  if (c.info.maxRayRecursionDepth < 2) {
    return Error{ErrorCode::MissingFeature, VK_SUCCESS,
                 "ReflectionPass needs a ray recursion depth of 2 (a shadow ray from each hit); the device allows " +
                     std::to_string(c.info.maxRayRecursionDepth)};
  }
  auto impl = std::make_unique<Impl>(context);
  // Set 1: the engine's textures, bindless. Partially bound with a variable count, so a table of any size up
  // to kMaxTextures (none included) fits one layout.
  VkDescriptorSetLayoutBinding textures{0, VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, kMaxTextures,
                                        VK_SHADER_STAGE_CLOSEST_HIT_BIT_KHR, nullptr};
  VkDescriptorBindingFlags flags = VK_DESCRIPTOR_BINDING_PARTIALLY_BOUND_BIT |
                                   VK_DESCRIPTOR_BINDING_VARIABLE_DESCRIPTOR_COUNT_BIT;
  VkDescriptorSetLayoutBindingFlagsCreateInfo flagsInfo{
      VK_STRUCTURE_TYPE_DESCRIPTOR_SET_LAYOUT_BINDING_FLAGS_CREATE_INFO};
  flagsInfo.bindingCount = 1;
  flagsInfo.pBindingFlags = &flags;
  VkDescriptorSetLayoutCreateInfo sl{VK_STRUCTURE_TYPE_DESCRIPTOR_SET_LAYOUT_CREATE_INFO, &flagsInfo};
  sl.bindingCount = 1;
  sl.pBindings = &textures;
  VkResult r = c.vk.vkCreateDescriptorSetLayout(c.desc.device, &sl, c.allocator(), &impl->textureLayout);
  if (r != VK_SUCCESS) return vulkanError(r, "vkCreateDescriptorSetLayout (reflection textures)");
  VkSamplerCreateInfo si{VK_STRUCTURE_TYPE_SAMPLER_CREATE_INFO};
  si.magFilter = si.minFilter = VK_FILTER_LINEAR;
  si.mipmapMode = VK_SAMPLER_MIPMAP_MODE_LINEAR;
  si.addressModeU = si.addressModeV = si.addressModeW = VK_SAMPLER_ADDRESS_MODE_REPEAT;
  si.maxLod = VK_LOD_CLAMP_NONE;
  r = c.vk.vkCreateSampler(c.desc.device, &si, c.allocator(), &impl->textureSampler);
  if (r != VK_SUCCESS) return vulkanError(r, "vkCreateSampler (reflection textures)");

  RayTracingPipelineDesc p;
  p.name = "reflection pass";
  p.raygen = SpirvModule::of(spirv::reflect_rgen);
  p.misses = {SpirvModule::of(spirv::reflect_rmiss), SpirvModule::of(spirv::occlusion_rmiss)};
  p.hitGroups = {HitGroupDesc{SpirvModule::of(spirv::reflect_rchit), {}}};
  p.maxRecursionDepth = 2;
  const VkShaderStageFlags rg = VK_SHADER_STAGE_RAYGEN_BIT_KHR;
  const VkShaderStageFlags hit = VK_SHADER_STAGE_CLOSEST_HIT_BIT_KHR;
  p.bindings = PassCore::commonBindings();
  p.bindings[RB_BINDING_TLAS].stageFlags |= hit;          // shadow rays from hits
  p.bindings[RB_BINDING_RAY_COUNTERS].stageFlags |= hit;  // and their count
  p.bindings.push_back(
      {RB_REFLECTION_BINDING_ROUGHNESS_METALNESS, VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, 1, rg, nullptr});
  p.bindings.push_back({RB_REFLECTION_BINDING_RADIANCE, VK_DESCRIPTOR_TYPE_STORAGE_IMAGE, 1, rg, nullptr});
  p.bindings.push_back({RB_REFLECTION_BINDING_SHADING_RECORDS, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 1, hit, nullptr});
  p.bindings.push_back({RB_REFLECTION_BINDING_MATERIALS, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 1, hit, nullptr});
  static_assert(RB_REFLECTION_SET_TEXTURES == 1, "the texture set is the first extra set");
  p.extraSetLayouts = {impl->textureLayout};
  p.pushConstantBytes = sizeof(ReflectionConstants);
  if (Status s = impl->core.init(context, p); !s) return s.error();
  // An empty table until the engine gives its own: every instance then shades with material 0, white.
  std::unique_ptr<ReflectionPass> pass(new ReflectionPass(std::move(impl)));
  Material defaultMaterial;
  if (Status s = pass->setMaterials(std::span(&defaultMaterial, 1), {}); !s) return s.error();
  return pass;
}

Status ReflectionPass::setMaterials(std::span<const Material> materials, std::span<const VkImageView> textures) {
  Impl& s = *impl_;
  Context::Impl& c = internal::contextImpl(s.ctx);
  auto invalid = [](const std::string& m) {
    return Error{ErrorCode::InvalidArgument, VK_SUCCESS, "ReflectionPass::setMaterials: " + m};
  };
  if (materials.empty()) return invalid("at least one material is needed (instances index the table)");
  if (textures.size() > kMaxTextures) {
    return invalid(std::to_string(textures.size()) + " textures exceed the limit of " + std::to_string(kMaxTextures));
  }
  for (size_t i = 0; i < materials.size(); ++i) {
    for (uint32_t t :
         {materials[i].baseColorTexture, materials[i].metallicRoughnessTexture, materials[i].emissiveTexture}) {
      if (t != kNoTexture && t >= textures.size()) {
        return invalid("materials[" + std::to_string(i) + "] uses texture " + std::to_string(t) + " but only " +
                       std::to_string(textures.size()) + " textures were given");
      }
    }
  }
  for (size_t i = 0; i < textures.size(); ++i) {
    if (!textures[i]) return invalid("textures[" + std::to_string(i) + "] is VK_NULL_HANDLE");
  }
  Result<GpuBuffer> buffer = createBuffer(s.ctx, materials.size() * sizeof(GpuMaterial),
                                          VK_BUFFER_USAGE_STORAGE_BUFFER_BIT, MemoryLocation::HostVisible,
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
    return vulkanError(r, "vkCreateDescriptorPool (reflection textures)");
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
    return vulkanError(r, "vkAllocateDescriptorSets (reflection textures)");
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

Status ReflectionPass::record(VkCommandBuffer cmd, const GBufferDesc& g, const TlasInfo& tlas,
                              const ReflectionSettings& settings) {
  Impl& s = *impl_;
  auto invalid = [](const std::string& m) {
    return Error{ErrorCode::InvalidArgument, VK_SUCCESS, "ReflectionPass: " + m};
  };
  if (!cmd) return invalid("cmd is VK_NULL_HANDLE");
  if (!tlas.shadingRecords) {
    return invalid("the TLAS has no shading records; build it with TlasBuildOptions::writeShadingRecords = true");
  }
  if (!g.roughnessInNormalW && !g.roughnessMetalness.view) {
    return invalid("the G-buffer has no roughness: set GBufferDesc::roughnessInNormalW or roughnessMetalness");
  }
  float threshold = settings.roughnessThreshold == 0.0f ? kDefaultReflectionRoughnessThreshold
                                                        : settings.roughnessThreshold;
  if (!(threshold > 0.0f && threshold <= 1.0f)) {
    return invalid("ReflectionSettings::roughnessThreshold " + std::to_string(threshold) + " is outside (0, 1]");
  }
  if (settings.raysPerPixel > 64) return invalid("ReflectionSettings::raysPerPixel exceeds 64");
  const bool sunUnset = settings.sunDirection[0] == 0.0f && settings.sunDirection[1] == 0.0f &&
                        settings.sunDirection[2] == 0.0f;
  const float sunDirection[3] = {settings.sunDirection[0], sunUnset ? 1.0f : settings.sunDirection[1],
                                 settings.sunDirection[2]};
  float sunLen = std::sqrt(sunDirection[0] * sunDirection[0] + sunDirection[1] * sunDirection[1] +
                           sunDirection[2] * sunDirection[2]);
  if (!std::isfinite(sunLen)) return invalid("ReflectionSettings::sunDirection must be finite");
  // Zero means the default, unless the engine says its zeros are meant (a black sky, no sky light).
  const bool explicitLighting = (settings.flags & kReflectionExplicitLighting) != 0;
  auto isZero = [](const float c[3]) { return c[0] == 0.0f && c[1] == 0.0f && c[2] == 0.0f; };
  const bool defaultSun = !explicitLighting && isZero(settings.sunRadiance);
  const bool defaultSky = !explicitLighting && isZero(settings.skyRadiance);
  ReflectionConstants pc{};
  if (Status st = fillGBufferConstants(g, tlas, s.ctx.frameIndex(), "ReflectionPass", pc.gbuffer); !st) return st;
  for (int i = 0; i < 3; ++i) {
    pc.sunDirection[i] = sunDirection[i] / sunLen;
    pc.sunRadiance[i] = defaultSun ? kDefaultSunRadiance : settings.sunRadiance[i];
    pc.skyRadiance[i] = defaultSky ? kDefaultSkyRadiance[i] : settings.skyRadiance[i];
  }
  pc.roughnessThreshold = threshold;
  pc.ambientIntensity = settings.ambientIntensity == 0.0f && !explicitLighting ? kDefaultAmbientIntensity
                                                                               : settings.ambientIntensity;
  pc.raysPerPixel = settings.raysPerPixel ? settings.raysPerPixel : kDefaultReflectionRays;

  if (Status st = s.core.begin(s.ctx, cmd, g, {{VK_FORMAT_R16G16B16A16_SFLOAT, "reflection radiance"}}); !st) return st;
  DescriptorWrites w;
  s.core.writeCommon(s.ctx, w, g, tlas);
  const GBufferImage& rm = g.roughnessMetalness.view ? g.roughnessMetalness : g.normal;
  w.sampledImage(RB_REFLECTION_BINDING_ROUGHNESS_METALNESS, rm.view, s.core.sampler, readLayout(rm));
  w.storageImage(RB_REFLECTION_BINDING_RADIANCE, s.core.images[0].view);
  w.storageBuffer(RB_REFLECTION_BINDING_SHADING_RECORDS, tlas.shadingRecords, 0, tlas.shadingRecordsBytes);
  w.storageBuffer(RB_REFLECTION_BINDING_MATERIALS, s.materials.buffer, 0, s.materials.size);
  s.core.pipeline.bind(s.ctx, cmd, w.writes, &pc, sizeof pc);
  internal::deviceFunctions(s.ctx).vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_RAY_TRACING_KHR,
                                                           s.core.pipeline.layout, RB_REFLECTION_SET_TEXTURES, 1,
                                                           &s.textureSet, 0, nullptr);
  s.core.pipeline.trace(s.ctx, cmd, g.width, g.height);
  s.core.images.endWrite(s.ctx, cmd);
  s.core.metrics.writeEnd(s.ctx, cmd);
  s.outputs.radiance = s.core.images[0].image;
  s.outputs.radianceView = s.core.images[0].view;
  s.outputs.width = g.width;
  s.outputs.height = g.height;
  return {};
}

const ReflectionOutputs& ReflectionPass::outputs() const { return impl_->outputs; }
PassStats ReflectionPass::stats() const { return impl_->core.metrics.latest(impl_->ctx); }

}  // namespace rb
