// Scene upload: everything goes through one staging buffer and one command buffer.
#include "gpu_scene.h"

#include <algorithm>
#include <cstring>

#include "vk_check.h"

namespace sample_engine::detail {
namespace {

struct VertexAttributes {  // 36 bytes, matches the pipelines' binding 1
  glm::vec3 normal;
  glm::vec2 uv;
  glm::vec4 tangent;
};
static_assert(sizeof(VertexAttributes) == 36);

struct Upload {
  VkBuffer dst;
  VkDeviceSize srcOffset, size;
};
struct TextureUpload {
  Image* image;
  VkDeviceSize srcOffset;
};

uint32_t mipCount(uint32_t w, uint32_t h) {
  uint32_t n = 1;
  while ((w | h) >> n) ++n;
  return n;
}

// Copies level 0 from the staging buffer, builds the mip chain by blits, leaves SHADER_READ_ONLY_OPTIMAL.
void recordTextureUpload(VkCommandBuffer cmd, VkBuffer staging, const TextureUpload& t) {
  Image& img = *t.image;
  imageBarrier(cmd, img.image, VK_IMAGE_ASPECT_COLOR_BIT, VK_IMAGE_LAYOUT_UNDEFINED,
               VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, VK_PIPELINE_STAGE_2_NONE, 0, VK_PIPELINE_STAGE_2_ALL_TRANSFER_BIT,
               VK_ACCESS_2_TRANSFER_WRITE_BIT);
  VkBufferImageCopy copy{};
  copy.bufferOffset = t.srcOffset;
  copy.imageSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 0, 1};
  copy.imageExtent = {img.extent.width, img.extent.height, 1};
  vkCmdCopyBufferToImage(cmd, staging, img.image, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, 1, &copy);
  int32_t w = int32_t(img.extent.width), h = int32_t(img.extent.height);
  for (uint32_t level = 1; level < img.mipLevels; ++level) {
    VkImageMemoryBarrier2 b{VK_STRUCTURE_TYPE_IMAGE_MEMORY_BARRIER_2};
    b.srcStageMask = b.dstStageMask = VK_PIPELINE_STAGE_2_ALL_TRANSFER_BIT;
    b.srcAccessMask = VK_ACCESS_2_TRANSFER_WRITE_BIT;
    b.dstAccessMask = VK_ACCESS_2_TRANSFER_READ_BIT;
    b.oldLayout = VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL;
    b.newLayout = VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL;
    b.srcQueueFamilyIndex = b.dstQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED;
    b.image = img.image;
    b.subresourceRange = {VK_IMAGE_ASPECT_COLOR_BIT, level - 1, 1, 0, 1};
    VkDependencyInfo dep{VK_STRUCTURE_TYPE_DEPENDENCY_INFO};
    dep.imageMemoryBarrierCount = 1;
    dep.pImageMemoryBarriers = &b;
    vkCmdPipelineBarrier2(cmd, &dep);
    int32_t nw = std::max(w / 2, 1), nh = std::max(h / 2, 1);
    VkImageBlit blit{};
    blit.srcSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, level - 1, 0, 1};
    blit.srcOffsets[1] = {w, h, 1};
    blit.dstSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, level, 0, 1};
    blit.dstOffsets[1] = {nw, nh, 1};
    vkCmdBlitImage(cmd, img.image, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, img.image,
                   VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, 1, &blit, VK_FILTER_LINEAR);
    w = nw;
    h = nh;
  }
  // Levels 0..n-2 are TRANSFER_SRC, the last is TRANSFER_DST: move both groups to shader reads.
  VkImageMemoryBarrier2 b[2] = {{VK_STRUCTURE_TYPE_IMAGE_MEMORY_BARRIER_2}, {VK_STRUCTURE_TYPE_IMAGE_MEMORY_BARRIER_2}};
  uint32_t count = 0;
  if (img.mipLevels > 1) {
    b[count].oldLayout = VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL;
    b[count].srcAccessMask = VK_ACCESS_2_TRANSFER_READ_BIT;
    b[count].subresourceRange = {VK_IMAGE_ASPECT_COLOR_BIT, 0, img.mipLevels - 1, 0, 1};
    ++count;
  }
  b[count].oldLayout = VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL;
  b[count].srcAccessMask = VK_ACCESS_2_TRANSFER_WRITE_BIT;
  b[count].subresourceRange = {VK_IMAGE_ASPECT_COLOR_BIT, img.mipLevels - 1, 1, 0, 1};
  ++count;
  for (uint32_t i = 0; i < count; ++i) {
    b[i].srcStageMask = VK_PIPELINE_STAGE_2_ALL_TRANSFER_BIT;
    b[i].dstStageMask = VK_PIPELINE_STAGE_2_FRAGMENT_SHADER_BIT;
    b[i].dstAccessMask = VK_ACCESS_2_SHADER_SAMPLED_READ_BIT;
    b[i].newLayout = VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL;
    b[i].srcQueueFamilyIndex = b[i].dstQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED;
    b[i].image = img.image;
  }
  VkDependencyInfo dep{VK_STRUCTURE_TYPE_DEPENDENCY_INFO};
  dep.imageMemoryBarrierCount = count;
  dep.pImageMemoryBarriers = b;
  vkCmdPipelineBarrier2(cmd, &dep);
}

// Creates RGBA8 textures (UNORM + sRGB views) and uploads `pixels` (each width*height*4 bytes).
std::string uploadTextures(Gpu& gpu, bool mips, std::vector<std::pair<Image*, const TextureData*>> textures) {
  VkDeviceSize total = 0;
  for (auto& [img, data] : textures) total += data->rgba8.size();
  Buffer staging;
  if (std::string e = gpu.createBuffer(total, VK_BUFFER_USAGE_TRANSFER_SRC_BIT,
                                       VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT | VK_MEMORY_PROPERTY_HOST_COHERENT_BIT,
                                       staging);
      !e.empty())
    return e;
  std::vector<TextureUpload> uploads;
  VkDeviceSize offset = 0;
  std::string e;
  for (auto& [img, data] : textures) {
    ImageDesc desc{VK_FORMAT_R8G8B8A8_UNORM,
                   {data->width, data->height},
                   VK_IMAGE_USAGE_SAMPLED_BIT | VK_IMAGE_USAGE_TRANSFER_DST_BIT | VK_IMAGE_USAGE_TRANSFER_SRC_BIT,
                   VK_IMAGE_ASPECT_COLOR_BIT,
                   mips ? mipCount(data->width, data->height) : 1u,
                   VK_FORMAT_R8G8B8A8_SRGB};
    if (e = gpu.createImage(desc, *img); !e.empty()) break;
    std::memcpy(static_cast<char*>(staging.mapped) + offset, data->rgba8.data(), data->rgba8.size());
    uploads.push_back({img, offset});
    offset += data->rgba8.size();
  }
  if (e.empty())
    e = gpu.submitNow([&](VkCommandBuffer cmd) {
      for (const auto& u : uploads) recordTextureUpload(cmd, staging.buffer, u);
    });
  gpu.destroy(staging);
  return e;
}

bool canBlitMips(VkPhysicalDevice pd) {
  VkFormatProperties p;
  vkGetPhysicalDeviceFormatProperties(pd, VK_FORMAT_R8G8B8A8_UNORM, &p);
  const VkFormatFeatureFlags need = VK_FORMAT_FEATURE_BLIT_SRC_BIT | VK_FORMAT_FEATURE_BLIT_DST_BIT |
                                    VK_FORMAT_FEATURE_SAMPLED_IMAGE_FILTER_LINEAR_BIT;
  return (p.optimalTilingFeatures & need) == need;
}

}  // namespace

std::string DefaultImages::create(Gpu& gpu) {
  TextureData w{"white", 1, 1, {255, 255, 255, 255}};
  TextureData b{"black", 1, 1, {0, 0, 0, 0}};
  TextureData n{"flat normal", 1, 1, {128, 128, 255, 255}};
  return uploadTextures(gpu, false, {{&white, &w}, {&black, &b}, {&flatNormal, &n}});
}

void DefaultImages::destroy(Gpu& gpu) {
  gpu.destroy(white);
  gpu.destroy(black);
  gpu.destroy(flatNormal);
}

bool deforms(const Scene& scene, const Instance& instance) {
  return instance.skin >= 0 || scene.meshes[instance.mesh].morphed();
}

std::string uploadScene(Gpu& gpu, const VulkanContext& ctx, const Pipelines& pipelines, const DefaultImages& defaults,
                        const Scene& scene, ScenePose& pose, GpuScene& out) {
  out.cpu = scene;
  finalizeScene(out.cpu);
  const Scene& s = out.cpu;
  if (Status st = pose.reset(s); !st) return st.error;
  out.bounds = s.bounds();

  // --- Buffers ---
  VkBufferUsageFlags rtUsage = VK_BUFFER_USAGE_STORAGE_BUFFER_BIT;
  if (ctx.info.bufferDeviceAddress) {
    rtUsage |= VK_BUFFER_USAGE_SHADER_DEVICE_ADDRESS_BIT;
    if (ctx.accelerationStructureEnabled)
      rtUsage |= VK_BUFFER_USAGE_ACCELERATION_STRUCTURE_BUILD_INPUT_READ_ONLY_BIT_KHR;
  }
  // The deformation pass reads the bind pose of deforming meshes by device address, and the deformed buffers
  // start as copies of it.
  std::vector<bool> deformedMesh(s.meshes.size(), false);
  for (const Instance& inst : s.instances) deformedMesh[inst.mesh] = deformedMesh[inst.mesh] || deforms(s, inst);
  // The index buffers of deforming meshes are also read where their deformed positions are (an add-on's BLAS
  // builds on the async compute queue): concurrent over both families, like the deformed buffers.
  std::vector<uint32_t> sharedFamilies = {ctx.queueFamily};
  if (ctx.asyncComputeFamily != UINT32_MAX) sharedFamilies.push_back(ctx.asyncComputeFamily);
  std::vector<std::vector<VertexAttributes>> attributes(s.meshes.size());
  std::vector<BufferRequest> requests;
  out.buffers.resize(s.meshes.size());
  VkDeviceSize stagingSize = 0;
  for (size_t m = 0; m < s.meshes.size(); ++m) {
    const MeshData& mesh = s.meshes[m];
    attributes[m].resize(mesh.positions.size());
    for (size_t v = 0; v < mesh.positions.size(); ++v)
      attributes[m][v] = {mesh.normals[v], mesh.uvs[v], mesh.tangents[v]};
    stagingSize += mesh.positions.size() * 12 + attributes[m].size() * 36 + mesh.indices.size() * 4;
    const VkBufferUsageFlags vertexUsage = VK_BUFFER_USAGE_VERTEX_BUFFER_BIT | VK_BUFFER_USAGE_TRANSFER_DST_BIT |
                                           VK_BUFFER_USAGE_TRANSFER_SRC_BIT | rtUsage |
                                           (deformedMesh[m] ? VK_BUFFER_USAGE_SHADER_DEVICE_ADDRESS_BIT : 0);
    MeshBuffers& b = out.buffers[m];
    if (!mesh.positions.empty()) {
      requests.push_back({mesh.positions.size() * 12, vertexUsage, &b.positions, {}});
      requests.push_back({mesh.positions.size() * 36, vertexUsage, &b.attributes, {}});
    }
    if (!mesh.indices.empty())
      requests.push_back({mesh.indices.size() * 4,
                          VK_BUFFER_USAGE_INDEX_BUFFER_BIT | VK_BUFFER_USAGE_TRANSFER_DST_BIT | rtUsage, &b.indices,
                          deformedMesh[m] ? std::span<const uint32_t>(sharedFamilies) : std::span<const uint32_t>()});
  }
  if (std::string e = gpu.createBuffers(requests, out.memoryBlocks); !e.empty()) return e;
  Buffer staging;
  if (std::string e = gpu.createBuffer(stagingSize, VK_BUFFER_USAGE_TRANSFER_SRC_BIT,
                                       VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT | VK_MEMORY_PROPERTY_HOST_COHERENT_BIT,
                                       staging);
      !e.empty())
    return e;
  std::vector<Upload> uploads;
  VkDeviceSize offset = 0;
  auto stage = [&](const void* data, VkDeviceSize size, const Buffer& dst) {
    if (size == 0) return;
    std::memcpy(static_cast<char*>(staging.mapped) + offset, data, size);
    uploads.push_back({dst.buffer, offset, size});
    offset += size;
  };
  out.meshes.resize(s.meshes.size());
  for (size_t m = 0; m < s.meshes.size(); ++m) {
    const MeshData& mesh = s.meshes[m];
    MeshBuffers& b = out.buffers[m];
    stage(mesh.positions.data(), mesh.positions.size() * 12, b.positions);
    stage(attributes[m].data(), attributes[m].size() * 36, b.attributes);
    stage(mesh.indices.data(), mesh.indices.size() * 4, b.indices);
    GpuMesh& g = out.meshes[m];
    g.positionBuffer = b.positions.buffer;
    g.positionAddress = ctx.info.bufferDeviceAddress ? b.positions.address : 0;
    g.attributeBuffer = b.attributes.buffer;
    g.attributeAddress = ctx.info.bufferDeviceAddress ? b.attributes.address : 0;
    g.indexBuffer = b.indices.buffer;
    g.indexAddress = b.indices.address;
    g.indexType = mesh.indices.empty() ? VK_INDEX_TYPE_NONE_KHR : VK_INDEX_TYPE_UINT32;
    g.vertexCount = uint32_t(mesh.positions.size());
    g.indexCount = uint32_t(mesh.indices.size());
    g.material = mesh.material;
    g.cpu = &mesh;
  }
  std::string e;
  if (!uploads.empty())
    e = gpu.submitNow([&](VkCommandBuffer cmd) {
      for (const Upload& u : uploads) {
        VkBufferCopy c{u.srcOffset, 0, u.size};
        vkCmdCopyBuffer(cmd, staging.buffer, u.dst, 1, &c);
      }
      // Later readers: vertex input, index input and any add-on (AS builds, shaders).
      memoryBarrier(cmd, VK_PIPELINE_STAGE_2_ALL_TRANSFER_BIT, VK_ACCESS_2_TRANSFER_WRITE_BIT,
                    VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT, VK_ACCESS_2_MEMORY_READ_BIT);
    });
  gpu.destroy(staging);
  if (!e.empty()) return e;

  // --- Per-instance draw data: rest transforms and the mesh's own buffers until deformation takes over ---
  out.instanceTransforms.resize(s.instances.size());
  out.instanceVertices.resize(s.instances.size());
  for (size_t i = 0; i < s.instances.size(); ++i) {
    out.instanceTransforms[i] = s.instances[i].transform;
    const MeshBuffers& b = out.buffers[s.instances[i].mesh];
    out.instanceVertices[i] = {b.positions.buffer, b.attributes.buffer, b.positions.buffer};
    const AlphaMode mode = s.materials[s.meshes[s.instances[i].mesh].material].alphaMode;
    out.instancesByAlpha[size_t(mode)].push_back(uint32_t(i));  // finalizeScene: Opaque, Mask or Blend
  }
  out.meshCenters.resize(s.meshes.size());
  out.meshRadii.resize(s.meshes.size());
  for (size_t m = 0; m < s.meshes.size(); ++m) {
    Bounds local;
    for (const glm::vec3& p : s.meshes[m].positions) local.extend(p);
    out.meshCenters[m] = local.valid() ? local.center() : glm::vec3(0.0f);
    out.meshRadii[m] = local.valid() ? local.radius() : 0.0f;
  }

  // --- Textures ---
  out.textures.resize(s.textures.size());
  std::vector<std::pair<Image*, const TextureData*>> textures;
  for (size_t t = 0; t < s.textures.size(); ++t)
    if (!s.textures[t].rgba8.empty()) textures.push_back({&out.textures[t], &s.textures[t]});
  if (!textures.empty())
    if (e = uploadTextures(gpu, canBlitMips(ctx.physicalDevice), textures); !e.empty()) return e;
  out.textureViews.resize(out.textures.size());
  for (size_t t = 0; t < out.textures.size(); ++t) {
    const Image& img = out.textures[t];
    if (img.image)
      out.textureViews[t] = {img.image, img.altView, img.view, img.extent.width, img.extent.height, img.mipLevels};
  }

  // --- Materials ---
  const uint32_t materialCount = uint32_t(s.materials.size());
  VkDescriptorPoolSize poolSize{VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, kMaterialSetBindings * materialCount};
  VkDescriptorPoolCreateInfo pci{VK_STRUCTURE_TYPE_DESCRIPTOR_POOL_CREATE_INFO};
  pci.maxSets = materialCount;
  pci.poolSizeCount = 1;
  pci.pPoolSizes = &poolSize;
  SE_VK_TRY(vkCreateDescriptorPool(gpu.device(), &pci, nullptr, &out.materialPool));
  std::vector<VkDescriptorSetLayout> layouts(materialCount, pipelines.materialSetLayout);
  out.materialSets.resize(materialCount);
  VkDescriptorSetAllocateInfo ai{VK_STRUCTURE_TYPE_DESCRIPTOR_SET_ALLOCATE_INFO};
  ai.descriptorPool = out.materialPool;
  ai.descriptorSetCount = materialCount;
  ai.pSetLayouts = layouts.data();
  SE_VK_TRY(vkAllocateDescriptorSets(gpu.device(), &ai, out.materialSets.data()));
  out.materialConstants.resize(materialCount);
  for (uint32_t m = 0; m < materialCount; ++m) {
    const Material& mat = s.materials[m];
    auto view = [&](int texture, const Image& fallback, bool srgb) {
      if (texture < 0 || !out.textures[texture].image) return fallback.view;
      return srgb ? out.textures[texture].altView : out.textures[texture].view;
    };
    // Bindings of surface.glsl. A packed ORM texture is bound twice (metallic-roughness and occlusion).
    const VkImageLayout layout = VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL;
    const VkSampler sampler = pipelines.materialSampler;
    VkDescriptorImageInfo infos[kMaterialSetBindings] = {
        {sampler, view(mat.baseColorTexture, defaults.white, true), layout},
        {sampler, view(mat.metallicRoughnessTexture, defaults.white, false), layout},
        {sampler, view(mat.normalTexture, defaults.flatNormal, false), layout},
        {sampler, view(mat.emissiveTexture, defaults.white, true), layout},
        {sampler, view(mat.occlusionTexture, defaults.white, false), layout}};
    VkWriteDescriptorSet w{VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET};
    w.dstSet = out.materialSets[m];
    w.descriptorCount = kMaterialSetBindings;
    w.descriptorType = VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER;
    w.pImageInfo = infos;
    vkUpdateDescriptorSets(gpu.device(), 1, &w, 0, nullptr);
    DrawConstants& c = out.materialConstants[m];
    c.model = glm::mat4(1.0f);
    c.baseColorFactor = mat.baseColorFactor;
    // w: occlusion strength (the occlusion binding's R channel); 0 without an occlusion image (white is bound).
    const bool occlusion = mat.occlusionTexture >= 0 && out.textures[mat.occlusionTexture].image;
    // z: normal scale; 0 without a normal image, so the interpolated normal stays exact (the 1x1 flat default's
    // 128/255 would tilt it by 0.2 degrees, a 2% error in a grazing light's cosine).
    const bool normalMap = mat.normalTexture >= 0 && out.textures[mat.normalTexture].image;
    c.material = glm::vec4(mat.metallicFactor, mat.roughnessFactor, normalMap ? mat.normalScale : 0.0f,
                           occlusion ? std::clamp(mat.occlusionStrength, 0.0f, 1.0f) : 0.0f);
    c.emissive = mat.emissiveFactor;
    c.alphaMode = uint32_t(mat.alphaMode);
    c.alphaCutoff = mat.alphaCutoff;
    c.instance = 0;
  }
  return {};
}

void destroyScene(Gpu& gpu, GpuScene& scene) {
  for (MeshBuffers& b : scene.buffers) {
    gpu.destroy(b.positions);
    gpu.destroy(b.attributes);
    gpu.destroy(b.indices);
  }
  gpu.freeBlocks(scene.memoryBlocks);
  for (Image& i : scene.textures) gpu.destroy(i);
  if (scene.materialPool) vkDestroyDescriptorPool(gpu.device(), scene.materialPool, nullptr);
  scene = GpuScene{};
}

}  // namespace sample_engine::detail
