// Ray tracing pipeline plumbing shared by every pass: shader modules, one push-descriptor set layout, push
// constants, the pipeline and its shader binding table.
#pragma once

#include <cstdint>
#include <deque>
#include <span>
#include <vector>

#include "gpu_memory.h"

namespace rb {

struct SpirvModule {
  const uint32_t* code = nullptr;
  size_t bytes = 0;
  template <size_t N>
  static SpirvModule of(const uint32_t (&words)[N]) {
    return {words, N * sizeof(uint32_t)};
  }
};

struct HitGroupDesc {
  SpirvModule closestHit;  // optional (code == nullptr: none)
  SpirvModule anyHit;      // optional
};

struct RayTracingPipelineDesc {
  SpirvModule raygen;
  std::vector<SpirvModule> misses;
  std::vector<HitGroupDesc> hitGroups;
  std::vector<VkDescriptorSetLayoutBinding> bindings;  // set 0, pushed with vkCmdPushDescriptorSetKHR
  std::vector<VkDescriptorSetLayout> extraSetLayouts;  // sets 1.. (owned by the caller), bound by the caller
  uint32_t pushConstantBytes = 0;
  uint32_t maxRecursionDepth = 1;
  const char* name = "ray tracing pipeline";
};

class RayTracingPipeline {
 public:
  static Result<RayTracingPipeline> create(Context& ctx, const RayTracingPipelineDesc& desc);
  // Destroys now: only for a pipeline no recorded command buffer uses (a failed create()).
  void destroy(Context& ctx);
  // Hands the pipeline, its layouts and its shader binding table to the context's deferred release (frames in
  // flight may still trace with it); this object is left empty.
  void retire(Context& ctx);

  // Binds the pipeline, pushes `writes` into set 0 and the push constants.
  void bind(Context& ctx, VkCommandBuffer cmd, std::span<const VkWriteDescriptorSet> writes, const void* constants,
            uint32_t constantBytes) const;
  void trace(Context& ctx, VkCommandBuffer cmd, uint32_t width, uint32_t height, uint32_t depth = 1) const;
  // The launch size read on the GPU from a VkTraceRaysIndirectCommandKHR at `arguments` (a buffer device address).
  void traceIndirect(Context& ctx, VkCommandBuffer cmd, VkDeviceAddress arguments) const;

  VkPipeline pipeline = VK_NULL_HANDLE;
  VkPipelineLayout layout = VK_NULL_HANDLE;
  VkDescriptorSetLayout setLayout = VK_NULL_HANDLE;
  VkShaderStageFlags pushConstantStages = 0;
  GpuBuffer sbt;
  VkStridedDeviceAddressRegionKHR raygenRegion{}, missRegion{}, hitRegion{}, callableRegion{};
};

// Descriptor write helpers for push descriptors (dstSet is ignored by vkCmdPushDescriptorSetKHR).
struct DescriptorWrites {
  std::vector<VkWriteDescriptorSet> writes;
  // Deques: `writes` points into them, and push_back on a deque never moves existing elements.
  std::deque<VkDescriptorImageInfo> images;
  std::deque<VkDescriptorBufferInfo> buffers;
  std::deque<VkWriteDescriptorSetAccelerationStructureKHR> accels;
  std::deque<VkAccelerationStructureKHR> accelHandles;
  void accelerationStructure(uint32_t binding, VkAccelerationStructureKHR as);
  void storageImage(uint32_t binding, VkImageView view, VkImageLayout layout = VK_IMAGE_LAYOUT_GENERAL);
  void sampledImage(uint32_t binding, VkImageView view, VkSampler sampler, VkImageLayout layout);
  void storageBuffer(uint32_t binding, VkBuffer buffer, VkDeviceSize offset = 0, VkDeviceSize range = VK_WHOLE_SIZE);
};

}  // namespace rb
