// A pass's tile classifier (shadows): a compute pass over 8x8-pixel tiles that writes the outputs of the tiles
// where no pixel needs a ray and lists the others, with the arguments of the vkCmdTraceRaysIndirectKHR that
// traces them. Owns the compute pipeline, the tile list (4 bytes per tile after a 16-byte argument header) and the
// tile state of converged-tile skipping (4 bytes per tile, shadow_converged.glsl), sized by the image,
// MemoryCategory::PassBuffers.
#pragma once

#include <utility>
#include <vector>

#include "compute_pipeline.h"

namespace rb {

class TileClassifier {
 public:
  // `bindings`: set 0 of `shader`, its tile list included.
  Status init(Context& ctx, const SpirvModule& shader, const std::vector<VkDescriptorSetLayoutBinding>& bindings,
              uint32_t pushConstantBytes, const char* name);
  // Hands the pipeline and the tile list to the context's deferred release (frames in flight may still use them).
  void retire(Context& ctx);

  // (Re)allocates the tile list and state for a width x height image (the old ones are retired). `withList` false:
  // the state alone (a pass that skips converged tiles in its own launch: reflections), with no pipeline to init().
  Status ensure(Context& ctx, uint32_t width, uint32_t height, bool withList = true);
  // The tile list as a storage buffer at `binding`: the classifier's and the ray generation shader's.
  void writeList(DescriptorWrites& w, uint32_t binding) const;
  // The tile state as a storage buffer at `binding`.
  void writeState(DescriptorWrites& w, uint32_t binding) const;
  VkBuffer stateBuffer() const { return state_.buffer; }
  // Whether the tile state was (re)allocated since the last call: its contents are undefined until cleared.
  bool takeStateReset() { return std::exchange(stateReset_, false); }
  // Resets the trace arguments, classifies every tile, and makes the classifier's writes (outputs, list, arguments,
  // counters) visible to the ray tracing shaders and the indirect launch that follow. The pass's output images
  // must already be writable by compute shaders.
  void classify(Context& ctx, VkCommandBuffer cmd, const DescriptorWrites& w, const void* constants,
                uint32_t constantBytes) const;
  // The VkTraceRaysIndirectCommandKHR that classify() filled, for RayTracingPipeline::traceIndirect().
  VkDeviceAddress traceArguments() const { return list_.address; }

  static VkDeviceSize listBytes(uint32_t width, uint32_t height);

 private:
  ComputePipeline pipeline_;
  GpuBuffer list_;
  GpuBuffer state_;
  bool stateReset_ = false;
  uint32_t width_ = 0, height_ = 0;
};

}  // namespace rb
