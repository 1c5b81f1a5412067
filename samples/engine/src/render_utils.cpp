#include "render_utils.h"

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

void drawScene(VkCommandBuffer cmd, const GpuScene& scene, const Pipelines& p, DrawPass pass,
               const glm::dvec3& origin) {
  uint32_t boundMaterial = UINT32_MAX;
  for (size_t i = 0; i < scene.cpu.instances.size(); ++i) {
    const Instance& inst = scene.cpu.instances[i];
    const GpuMesh& mesh = scene.meshes[inst.mesh];
    if (mesh.vertexCount == 0) continue;
    // The instance's own deformed buffers when it deforms, else the mesh's.
    const VkBuffer* buffers = scene.instanceVertices[i].data();
    VkDeviceSize offsets[2] = {0, 0};
    vkCmdBindVertexBuffers(cmd, 0, pass == DrawPass::Shadow ? 1 : 2, buffers, offsets);
    if (pass != DrawPass::Shadow && boundMaterial != mesh.material) {
      vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, p.sceneLayout, 1, 1,
                              &scene.materialSets[mesh.material], 0, nullptr);
      boundMaterial = mesh.material;
    }
    DrawConstants c = scene.materialConstants[mesh.material];
    c.model = rebasedTransform(scene.instanceTransforms[i], origin);
    vkCmdPushConstants(cmd, p.sceneLayout, VK_SHADER_STAGE_VERTEX_BIT | VK_SHADER_STAGE_FRAGMENT_BIT, 0, sizeof(c), &c);
    if (mesh.indexCount > 0) {
      vkCmdBindIndexBuffer(cmd, mesh.indexBuffer, 0, VK_INDEX_TYPE_UINT32);
      vkCmdDrawIndexed(cmd, mesh.indexCount, 1, 0, 0, 0);
    } else {
      vkCmdDraw(cmd, mesh.vertexCount, 1, 0, 0);
    }
  }
}

void writeImageDescriptors(VkDevice device, VkDescriptorSet set, const std::vector<VkDescriptorImageInfo>& infos) {
  std::vector<VkWriteDescriptorSet> writes(infos.size(), {VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET});
  for (size_t i = 0; i < infos.size(); ++i) {
    writes[i].dstSet = set;
    writes[i].dstBinding = uint32_t(i);
    writes[i].descriptorCount = 1;
    writes[i].descriptorType = VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER;
    writes[i].pImageInfo = &infos[i];
  }
  vkUpdateDescriptorSets(device, uint32_t(writes.size()), writes.data(), 0, nullptr);
}

void drawFullscreen(VkCommandBuffer cmd, const Pipelines& p, VkPipeline pipeline, VkDescriptorSet frameSet,
                    VkDescriptorSet inputSet, const SsaoConstants& constants, VkImageView target, VkExtent2D extent) {
  beginRendering(cmd, extent, {colorAttachment(target, {{1.0f, 1.0f, 1.0f, 1.0f}})}, nullptr);
  vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, pipeline);
  VkDescriptorSet sets[2] = {frameSet, inputSet};
  vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, p.screenLayout, 0, 2, sets, 0, nullptr);
  vkCmdPushConstants(cmd, p.screenLayout, VK_SHADER_STAGE_FRAGMENT_BIT, 0, sizeof(constants), &constants);
  vkCmdDraw(cmd, 3, 1, 0, 0);
  vkCmdEndRendering(cmd);
}

}  // namespace sample_engine::detail
