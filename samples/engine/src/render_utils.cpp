#include "render_utils.h"

#include <algorithm>
#include <utility>

namespace sample_engine::detail {

VkRenderingAttachmentInfo colorAttachment(VkImageView view, VkClearColorValue clear) {
  VkRenderingAttachmentInfo a{VK_STRUCTURE_TYPE_RENDERING_ATTACHMENT_INFO};
  a.imageView = view;
  a.imageLayout = VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL;
  a.loadOp = VK_ATTACHMENT_LOAD_OP_CLEAR;
  a.storeOp = VK_ATTACHMENT_STORE_OP_STORE;
  a.clearValue.color = clear;
  return a;
}

void beginRendering(VkCommandBuffer cmd, VkExtent2D extent, const std::vector<VkRenderingAttachmentInfo>& colors,
                    const VkRenderingAttachmentInfo* depth) {
  VkRenderingInfo ri{VK_STRUCTURE_TYPE_RENDERING_INFO};
  ri.renderArea = {{0, 0}, extent};
  ri.layerCount = 1;
  ri.colorAttachmentCount = uint32_t(colors.size());
  ri.pColorAttachments = colors.data();
  ri.pDepthAttachment = depth;
  vkCmdBeginRendering(cmd, &ri);
  VkViewport vp{0.0f, 0.0f, float(extent.width), float(extent.height), 0.0f, 1.0f};
  VkRect2D scissor{{0, 0}, extent};
  vkCmdSetViewport(cmd, 0, 1, &vp);
  vkCmdSetScissor(cmd, 0, 1, &scissor);
}

glm::mat4 rebasedTransform(const glm::mat4& world, const glm::dvec3& origin) {
  // translate(-origin) * world: every column loses origin times its w (1 for the translation, 0 otherwise).
  glm::mat4 out = world;
  for (int c = 0; c < 4; ++c)
    for (int r = 0; r < 3; ++r) out[c][r] = float(double(world[c][r]) - origin[r] * double(world[c][3]));
  return out;
}

namespace {

// Front faces wind counter-clockwise in a camera's image (glTF, the procedural meshes); a model matrix with a
// negative determinant (a mirrored instance) and a mirrored view each reverse that.
VkFrontFace frontFaceOf(const glm::mat4& model, ViewHandedness view) {
  const bool mirrored = (glm::determinant(glm::mat3(model)) < 0.0f) != (view == ViewHandedness::MirroredCubeFace);
  return mirrored ? VK_FRONT_FACE_CLOCKWISE : VK_FRONT_FACE_COUNTER_CLOCKWISE;
}

// Binds what instance `i` needs (vertex buffers, its material set unless `positionsOnly`), pushes its
// constants and draws it.
void drawInstance(VkCommandBuffer cmd, const GpuScene& scene, const Pipelines& p, uint32_t i, const glm::mat4& model,
                  bool positionsOnly, uint32_t& boundMaterial) {
  const GpuMesh& mesh = scene.meshes[scene.cpu.instances[i].mesh];
  // The instance's own deformed buffers when it deforms, else the mesh's.
  const VkBuffer* buffers = scene.instanceVertices[i].data();
  VkDeviceSize offsets[3] = {0, 0, 0};
  vkCmdBindVertexBuffers(cmd, 0, positionsOnly ? 1 : 3, buffers, offsets);
  if (!positionsOnly && boundMaterial != mesh.material) {
    vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, p.sceneLayout, 1, 1,
                            &scene.materialSets[mesh.material], 0, nullptr);
    boundMaterial = mesh.material;
  }
  DrawConstants c = scene.materialConstants[mesh.material];
  c.model = model;
  c.instance = i;
  c.previousModels = scene.previousModels;
  vkCmdPushConstants(cmd, p.sceneLayout, VK_SHADER_STAGE_VERTEX_BIT | VK_SHADER_STAGE_FRAGMENT_BIT, 0, sizeof(c), &c);
  if (mesh.indexCount > 0) {
    vkCmdBindIndexBuffer(cmd, mesh.indexBuffer, 0, VK_INDEX_TYPE_UINT32);
    vkCmdDrawIndexed(cmd, mesh.indexCount, 1, 0, 0, 0);
  } else {
    vkCmdDraw(cmd, mesh.vertexCount, 1, 0, 0);
  }
}

bool drawable(const GpuScene& scene, uint32_t i) { return scene.meshes[scene.cpu.instances[i].mesh].vertexCount > 0; }

const Material& materialOf(const GpuScene& scene, uint32_t i) {
  return scene.cpu.materials[scene.meshes[scene.cpu.instances[i].mesh].material];
}

}  // namespace

namespace {

// Whether instance i can touch `sphere` (relative to origin; w <= 0 = everything can). Deforming instances
// always can: their bind-pose bounds say nothing about this frame's shape. A caster wholly outside a light's
// range sphere cannot block a receiver inside it (the segment between them stays inside the sphere).
bool reaches(const GpuScene& scene, uint32_t i, const glm::dvec3& origin, const glm::vec4& sphere) {
  if (sphere.w <= 0.0f || deforms(scene.cpu, scene.cpu.instances[i])) return true;
  const glm::mat4& world = scene.instanceTransforms[i];
  const uint32_t mesh = scene.cpu.instances[i].mesh;
  const glm::dvec3 center = glm::dvec3(glm::dmat4(world) * glm::dvec4(scene.meshCenters[mesh], 1.0)) - origin;
  const float scale = std::max(
      {glm::length(glm::vec3(world[0])), glm::length(glm::vec3(world[1])), glm::length(glm::vec3(world[2]))});
  const double reach = double(sphere.w) + double(scene.meshRadii[mesh]) * double(scale);
  const glm::dvec3 d = center - glm::dvec3(sphere);
  return glm::dot(d, d) <= reach * reach;
}

}  // namespace

void drawScene(VkCommandBuffer cmd, const GpuScene& scene, const Pipelines& p, DrawPass pass,
               const PassPipelines& pipelines, const glm::dvec3& origin, ViewHandedness view,
               const glm::vec4& casterSphere) {
  const auto& opaque = scene.instancesByAlpha[size_t(AlphaMode::Opaque)];
  const auto& masked = scene.instancesByAlpha[size_t(AlphaMode::Mask)];
  const auto& blended = scene.instancesByAlpha[size_t(AlphaMode::Blend)];
  uint32_t boundMaterial = UINT32_MAX;
  if (pass == DrawPass::Shadow) {
    // No culling (see Pipelines::create). Opaque casters need positions only; the others their alpha test.
    auto draw = [&](const std::vector<uint32_t>& list, VkPipeline pipeline, bool positionsOnly) {
      bool bound = false;
      for (uint32_t i : list) {
        if (!drawable(scene, i) || !reaches(scene, i, origin, casterSphere)) continue;
        if (!bound) vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, pipeline);
        bound = true;
        drawInstance(cmd, scene, p, i, rebasedTransform(scene.instanceTransforms[i], origin), positionsOnly,
                     boundMaterial);
      }
    };
    draw(opaque, p.shadow, true);
    draw(masked, p.shadowAlpha, false);
    draw(blended, p.shadowAlpha, false);
    return;
  }
  for (const auto& [list, pipeline] : {std::pair{&opaque, pipelines.opaque}, std::pair{&masked, pipelines.masked}}) {
    bool bound = false;
    for (uint32_t i : *list) {
      if (!drawable(scene, i)) continue;
      if (!bound) vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, pipeline);
      bound = true;
      const glm::mat4 model = rebasedTransform(scene.instanceTransforms[i], origin);
      // Single-sided (glTF doubleSided false): back faces are culled. Double-sided: both sides are drawn and
      // surface.glsl turns the shading normal towards the viewer.
      vkCmdSetCullMode(cmd, materialOf(scene, i).doubleSided ? VK_CULL_MODE_NONE : VK_CULL_MODE_BACK_BIT);
      vkCmdSetFrontFace(cmd, frontFaceOf(model, view));
      drawInstance(cmd, scene, p, i, model, false, boundMaterial);
    }
  }
}

void drawBlended(VkCommandBuffer cmd, const GpuScene& scene, const Pipelines& p, const glm::dvec3& origin,
                 ViewHandedness view) {
  const auto& blended = scene.instancesByAlpha[size_t(AlphaMode::Blend)];
  if (blended.empty()) return;
  std::vector<std::pair<double, uint32_t>> order;  // squared distance, instance
  order.reserve(blended.size());
  for (uint32_t i : blended) {
    if (!drawable(scene, i)) continue;
    const glm::dvec4 center = glm::dmat4(scene.instanceTransforms[i]) *
                              glm::dvec4(scene.meshCenters[scene.cpu.instances[i].mesh], 1.0);
    const glm::dvec3 d = glm::dvec3(center) - origin;
    order.push_back({glm::dot(d, d), i});
  }
  std::stable_sort(order.begin(), order.end(), [](const auto& a, const auto& b) { return a.first > b.first; });
  vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, p.blend);
  uint32_t boundMaterial = UINT32_MAX;
  for (const auto& [distance, i] : order) {
    const glm::mat4 model = rebasedTransform(scene.instanceTransforms[i], origin);
    vkCmdSetFrontFace(cmd, frontFaceOf(model, view));
    if (materialOf(scene, i).doubleSided) {
      vkCmdSetCullMode(cmd, VK_CULL_MODE_FRONT_BIT);
      drawInstance(cmd, scene, p, i, model, false, boundMaterial);
    }
    vkCmdSetCullMode(cmd, VK_CULL_MODE_BACK_BIT);
    drawInstance(cmd, scene, p, i, model, false, boundMaterial);
  }
}

void writeImageDescriptors(VkDevice device, VkDescriptorSet set, const std::vector<VkDescriptorImageInfo>& infos,
                           uint32_t firstBinding) {
  std::vector<VkWriteDescriptorSet> writes(infos.size(), {VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET});
  for (size_t i = 0; i < infos.size(); ++i) {
    writes[i].dstSet = set;
    writes[i].dstBinding = firstBinding + uint32_t(i);
    writes[i].descriptorCount = 1;
    writes[i].descriptorType = VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER;
    writes[i].pImageInfo = &infos[i];
  }
  vkUpdateDescriptorSets(device, uint32_t(writes.size()), writes.data(), 0, nullptr);
}

void drawFullscreen(VkCommandBuffer cmd, const Pipelines& p, VkPipeline pipeline, VkDescriptorSet frameSet,
                    VkDescriptorSet inputSet, VkImageView target, VkExtent2D extent) {
  beginRendering(cmd, extent, {colorAttachment(target, {{1.0f, 1.0f, 1.0f, 1.0f}})}, nullptr);
  vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, pipeline);
  VkDescriptorSet sets[2] = {frameSet, inputSet};
  vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, p.screenLayout, 0, 2, sets, 0, nullptr);
  vkCmdDraw(cmd, 3, 1, 0, 0);
  vkCmdEndRendering(cmd);
}

void writeLocalLightDescriptors(VkDevice device, const Pipelines& p, VkDescriptorSet set, uint32_t firstBinding,
                                const LocalLightBindings& b) {
  const VkDescriptorImageInfo image{p.shadowSampler, b.shadowMaps, VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL};
  const VkDescriptorBufferInfo lights{b.lights, 0, b.lightsSize}, shadows{b.shadows, 0, b.shadowsSize};
  VkWriteDescriptorSet w[3];
  for (uint32_t i = 0; i < 3; ++i) {
    w[i] = VkWriteDescriptorSet{VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET};
    w[i].dstSet = set;
    w[i].dstBinding = firstBinding + i;
    w[i].descriptorCount = 1;
  }
  w[0].descriptorType = VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER;
  w[0].pImageInfo = &image;
  w[1].descriptorType = VK_DESCRIPTOR_TYPE_STORAGE_BUFFER;
  w[1].pBufferInfo = &lights;
  w[2].descriptorType = VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER;
  w[2].pBufferInfo = &shadows;
  vkUpdateDescriptorSets(device, 3, w, 0, nullptr);
}

}  // namespace sample_engine::detail
