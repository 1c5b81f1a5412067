// What every G-buffer ray tracing pass has: its pipeline, the G-buffer sampler, its output images and its
// measurements, with the recording steps they share.
#pragma once

#include <raybridge/acceleration_structures.h>
#include <raybridge/gbuffer.h>

#include "pass_constants.h"
#include "pass_images.h"
#include "pass_metrics.h"
#include "ray_tracing_pipeline.h"

namespace rb {

struct PassCore {
  RayTracingPipeline pipeline;
  VkSampler sampler = VK_NULL_HANDLE;
  PassImages images;
  PassMetrics metrics;

  Status init(Context& ctx, const RayTracingPipelineDesc& desc);
  // Hands the pipeline, sampler, images and measurement objects to the context's deferred release: the pass
  // may be destroyed while frames that recorded it are still in flight.
  void retire(Context& ctx);

  // The bindings every pass starts with (RB_BINDING_* in shaders/raybridge_shader_interface.glsl): TLAS, depth,
  // normal, geometric normal (or the normal), ray counters. Pass-specific bindings follow.
  static std::vector<VkDescriptorSetLayoutBinding> commonBindings();
  void writeCommon(Context& ctx, DescriptorWrites& w, const GBufferDesc& g, const TlasInfo& tlas) const;

  // Ensures the outputs, starts the measurements and makes the outputs writable.
  Status begin(Context& ctx, VkCommandBuffer cmd, const GBufferDesc& g, const std::vector<PassImages::Spec>& outputs);
  // Traces one ray generation invocation per G-buffer pixel with the pass's push constants (ShadowConstants,
  // AoConstants, ...), then makes the outputs readable.
  template <typename Constants>
  void traceAndEnd(Context& ctx, VkCommandBuffer cmd, const DescriptorWrites& w, const Constants& pc,
                   const GBufferDesc& g) {
    traceAndEnd(ctx, cmd, w, &pc, sizeof pc, g);
  }
  void traceAndEnd(Context& ctx, VkCommandBuffer cmd, const DescriptorWrites& w, const void* constants,
                   uint32_t constantBytes, const GBufferDesc& g);
};

}  // namespace rb
