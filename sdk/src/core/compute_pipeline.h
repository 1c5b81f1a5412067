// Compute pipeline plumbing for the image-space passes (the denoiser) and the BLAS cluster measure: one
// push-descriptor set (possibly empty) and push constants, like RayTracingPipeline.
#pragma once

#include <span>
#include <vector>

#include "ray_tracing_pipeline.h"

namespace rb {

class ComputePipeline {
 public:
  static Result<ComputePipeline> create(Context& ctx, const SpirvModule& shader,
                                        const std::vector<VkDescriptorSetLayoutBinding>& bindings,
                                        uint32_t pushConstantBytes, const char* name);
  // Destroys now: only for a pipeline no pending command buffer uses (a failed create(), or an owner whose
  // contract is that the GPU is done).
  void destroy(Context& ctx);
  // Hands the pipeline and its layouts to the context's deferred release (frames in flight may still
  // dispatch it); this object is left empty.
  void retire(Context& ctx);
  // Binds, pushes the descriptors and constants, and dispatches groupSide x groupSide groups over width x height
  // (groupSide: the shader's local size).
  void dispatch(Context& ctx, VkCommandBuffer cmd, std::span<const VkWriteDescriptorSet> writes, const void* constants,
                uint32_t constantBytes, uint32_t width, uint32_t height, uint32_t groupSide = 8) const;

  VkPipeline pipeline = VK_NULL_HANDLE;
  VkPipelineLayout layout = VK_NULL_HANDLE;
  VkDescriptorSetLayout setLayout = VK_NULL_HANDLE;
};

}  // namespace rb
