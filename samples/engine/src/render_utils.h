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

enum class DrawPass {
  Shadow,    // OPAQUE draws with Pipelines::shadow, MASK and BLEND with shadowAlpha; no culling
  Prepass,   // OPAQUE and MASK draws
  Lighting,  // OPAQUE and MASK draws (the main view's lighting, or the probe capture)
};

// Which way the pass's projection maps the world: Vulkan's cube-map faces (the probe capture) are mirror
// images of a camera's view, so counter-clockwise front faces appear clockwise there.
enum class ViewHandedness { Camera, MirroredCubeFace };

// The two pipelines of a camera pass (Pipelines' pairs): OPAQUE draws, MASK draws.
struct PassPipelines {
  VkPipeline opaque = VK_NULL_HANDLE;
  VkPipeline masked = VK_NULL_HANDLE;
};

// `world` with `origin` subtracted from its translation, in double precision, then rounded to float: the
// model matrix of a pass whose positions are relative to `origin` (the camera or the probe), so a vertex far
// from the world origin keeps float precision near the eye.
glm::mat4 rebasedTransform(const glm::mat4& world, const glm::dvec3& origin);

// One draw per instance of the pass's alpha modes (see DrawPass), grouped by pipeline (opaque first), with its
// GpuScene::instanceTransforms / instanceVertices entry (this frame's world transform rebased to `origin`,
// deformed buffers); binds the pipelines, vertex buffers, material sets (set 1, except for opaque shadow draws)
// and push constants, and in camera passes the face culling of each draw (Material::doubleSided, the model
// matrix's handedness, `view`). Shadow ignores `pipelines` and `view`. Set 0 (and set 2 for Lighting) must
// already be bound; for Shadow, the depth bias must be set.
// `casterSphere` (Shadow only; xyz relative to `origin`, w radius; w <= 0 = none): rigid instances whose
// bounding sphere misses it are not drawn (a range-limited light's shadow views skip what it cannot reach).
void drawScene(VkCommandBuffer cmd, const GpuScene& scene, const Pipelines& p, DrawPass pass,
               const PassPipelines& pipelines, const glm::dvec3& origin, ViewHandedness view = ViewHandedness::Camera,
               const glm::vec4& casterSphere = glm::vec4(0.0f));

// The BLEND draws with Pipelines::blend, back to front by the distance from `origin` to each instance's
// bounding-box centre (this frame's transform; ties keep the scene's order). A double-sided one is drawn
// twice, back faces first, so that a closed blended mesh composites its far side under its near side. Sets
// 0 and 2 must be bound, the opaque surfaces already drawn into the bound HDR and depth attachments.
void drawBlended(VkCommandBuffer cmd, const GpuScene& scene, const Pipelines& p, const glm::dvec3& origin,
                 ViewHandedness view = ViewHandedness::Camera);

// Writes infos[i] to binding firstBinding + i of `set` (combined image samplers).
void writeImageDescriptors(VkDevice device, VkDescriptorSet set, const std::vector<VkDescriptorImageInfo>& infos,
                           uint32_t firstBinding = 0);

// What the three descriptors of shaders/local_lights.glsl bind: the local shadow maps (2D array, SHADER_READ_ONLY
// OPTIMAL), the frame's KHR light buffer and its shadow views.
struct LocalLightBindings {
  VkImageView shadowMaps = VK_NULL_HANDLE;
  VkBuffer lights = VK_NULL_HANDLE;
  VkDeviceSize lightsSize = 0;
  VkBuffer shadows = VK_NULL_HANDLE;
  VkDeviceSize shadowsSize = 0;
};
// Writes them to bindings firstBinding .. firstBinding + 2 of `set`.
void writeLocalLightDescriptors(VkDevice device, const Pipelines& p, VkDescriptorSet set, uint32_t firstBinding,
                                const LocalLightBindings& bindings);

// Binds `pipeline` (a fullscreen pipeline of Pipelines::screenLayout) with `frameSet` / `inputSet`, and draws
// one triangle into `target` (cleared to 1: "lit" for the effect images). The target must be in
// COLOR_ATTACHMENT_OPTIMAL.
void drawFullscreen(VkCommandBuffer cmd, const Pipelines& p, VkPipeline pipeline, VkDescriptorSet frameSet,
                    VkDescriptorSet inputSet, VkImageView target, VkExtent2D extent);

}  // namespace sample_engine::detail
