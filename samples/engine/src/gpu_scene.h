// GPU copy of a Scene: vertex/index buffers per mesh, textures, one descriptor set per material.
#pragma once

#include <array>
#include <string>
#include <vector>

#include "gpu_memory.h"
#include "pipelines.h"
#include "sample_engine/animation.h"
#include "sample_engine/engine.h"
#include "vk_context.h"

namespace sample_engine::detail {

// 1x1 fallback textures bound where a material or lighting input has nothing.
struct DefaultImages {
  Image white;       // RGBA8 UNORM (1,1,1,1): base color, metallic-roughness, visibility, AO
  Image black;       // RGBA8 UNORM (0,0,0,0): reflection
  Image flatNormal;  // RGBA8 UNORM (0.5,0.5,1): tangent-space +Z
  std::string create(Gpu& gpu);
  void destroy(Gpu& gpu);
};

struct MeshBuffers {
  Buffer positions, attributes, indices;
};

struct GpuScene {
  Scene cpu;                         // finalized copy; GpuMesh::cpu points into it
  std::vector<MeshBuffers> buffers;  // bound into memoryBlocks
  std::vector<VkDeviceMemory> memoryBlocks;
  std::vector<GpuMesh> meshes;
  std::vector<Image> textures;
  std::vector<GpuTexture> textureViews;  // public view of `textures`
  VkDescriptorPool materialPool = VK_NULL_HANDLE;
  std::vector<VkDescriptorSet> materialSets;
  std::vector<DrawConstants> materialConstants;  // model matrix and instance filled per draw
  Bounds bounds;
  // Scene::instances indices by their material's AlphaMode (index = the enum's value), in scene order: what
  // each pass draws and with which pipeline.
  std::array<std::vector<uint32_t>, 3> instancesByAlpha;
  std::vector<glm::vec3> meshCenters;  // per mesh: its bounding-box centre (local), for sorting BLEND draws
  std::vector<float> meshRadii;        // per mesh: half its bounding-box diagonal (local), for culling casters
  // Per Scene instance, what the raster passes draw: this frame's world transform, and the position / attribute /
  // last frame's position buffers (the mesh's, the positions twice; or the instance's deformed buffers).
  std::vector<glm::mat4> instanceTransforms;
  std::vector<std::array<VkBuffer, 3>> instanceVertices;
  // Device address of this frame's copy of last frame's model matrices (DrawConstants::previousModels); 0 = none.
  uint64_t previousModels = 0;
};

// True for an instance the deformation pass writes own vertex buffers for: skinned and/or morphed.
bool deforms(const Scene& scene, const Instance& instance);

// Copies and finalizes `scene`, checks its animation data with pose.reset() (nothing is uploaded when that
// fails), then uploads it.
std::string uploadScene(Gpu& gpu, const VulkanContext& ctx, const Pipelines& pipelines, const DefaultImages& defaults,
                        const Scene& scene, ScenePose& pose, GpuScene& out);
void destroyScene(Gpu& gpu, GpuScene& scene);

}  // namespace sample_engine::detail
