// Small recording helpers shared by the frame recorder, the effect passes and the reflection-probe capture.
#pragma once

#include <vector>

#include <vulkan/vulkan.h>

#include "gpu_scene.h"
#include "pipelines.h"

namespace sample_engine::detail {

// Color attachment in COLOR_ATTACHMENT_OPTIMAL, cleared to `clear` and stored.
VkRenderingAttachmentInfo colorAttachment(VkImageView view, VkClearColorValue clear);

// Begins dynamic rendering over `extent` and sets the matching viewport and scissor.
void beginRendering(VkCommandBuffer cmd, VkExtent2D extent, const std::vector<VkRenderingAttachmentInfo>& colors,
                    const VkRenderingAttachmentInfo* depth);

enum class DrawPass { Shadow, Prepass, Lighting };

// `world` with `origin` subtracted from its translation, in double precision, then rounded to float: the
// model matrix of a pass whose positions are relative to `origin` (the camera or the probe), so a vertex far
// from the world origin keeps float precision near the eye.
glm::mat4 rebasedTransform(const glm::mat4& world, const glm::dvec3& origin);

// One draw per instance with its GpuScene::instanceTransforms / instanceVertices entry (this frame's world
// transform rebased to `origin`, deformed buffers); binds vertex buffers, material sets (set 1, except for
// Shadow) and push constants.
// Set 0 (and set 2 for Lighting) must already be bound.
void drawScene(VkCommandBuffer cmd, const GpuScene& scene, const Pipelines& p, DrawPass pass, const glm::dvec3& origin);

// Writes infos[i] to binding i of `set` (combined image samplers).
void writeImageDescriptors(VkDevice device, VkDescriptorSet set, const std::vector<VkDescriptorImageInfo>& infos);

// Binds `pipeline` (a fullscreen pipeline of Pipelines::screenLayout) with `frameSet` / `inputSet` and
// `constants`, and draws one triangle into `target` (cleared to 1: "open" / "lit" for the effect images).
// The target must be in COLOR_ATTACHMENT_OPTIMAL.
void drawFullscreen(VkCommandBuffer cmd, const Pipelines& p, VkPipeline pipeline, VkDescriptorSet frameSet,
                    VkDescriptorSet inputSet, const SsaoConstants& constants, VkImageView target, VkExtent2D extent);

}  // namespace sample_engine::detail
