// What every G-buffer ray tracing pass has: its pipeline, the G-buffer sampler, its output images and its
// measurements, with the recording steps they share.
#pragma once

#include <raybridge/acceleration_structures.h>
#include <raybridge/gbuffer.h>
#include <raybridge/material_table.h>

#include <memory>

#include "half_resolution.h"
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
  // Alpha testing (addMaterialBindings): the texture set's layout, and the table bound when the caller gives
  // none (the bindings are statically used by the any-hit shader, so they must be valid even unread).
  VkDescriptorSetLayout textureLayout = VK_NULL_HANDLE;
  std::unique_ptr<MaterialTable> fallbackMaterials;
  VkDescriptorSet boundTextures = VK_NULL_HANDLE;  // set RB_SET_TEXTURES of this recording

  // With `alphaAnyHit`, `desc`'s hit groups get that any-hit shader and the material bindings are added
  // (shading records, materials, texture set); `recordStages` are the stages besides any-hit that read them.
  Status init(Context& ctx, RayTracingPipelineDesc desc, SpirvModule alphaAnyHit = {},
              VkShaderStageFlags recordStages = 0);
  // Whether init() was given an any-hit shader (the material bindings exist, writeMaterials() fills them).
  bool alphaTested() const { return textureLayout != VK_NULL_HANDLE; }
  // Another pipeline of the pass with the same alpha testing (a variant of its ray generation module, e.g. with
  // adaptive rays), sharing this core's texture set layout, images and measurements. The caller retires it.
  Result<RayTracingPipeline> createVariant(Context& ctx, RayTracingPipelineDesc desc, SpirvModule alphaAnyHit = {},
                                           VkShaderStageFlags recordStages = 0) const;
  // What init() and createVariant() add to a pipeline for alpha testing: the any-hit shader, the material
  // bindings and the texture set layout.
  void addAlphaTest(RayTracingPipelineDesc& desc, SpirvModule alphaAnyHit, VkShaderStageFlags recordStages) const;
  // Hands the pipeline, sampler, images and measurement objects to the context's deferred release: the pass
  // may be destroyed while frames that recorded it are still in flight.
  void retire(Context& ctx);

  // The bindings every pass starts with (RB_BINDING_* in shaders/raybridge_shader_interface.glsl): TLAS, depth,
  // normal, geometric normal (or the normal), ray counters. Pass-specific bindings follow.
  static std::vector<VkDescriptorSetLayoutBinding> commonBindings();
  void writeCommon(Context& ctx, DescriptorWrites& w, const GBufferDesc& g, const TlasInfo& tlas) const;
  // The common bindings but the TLAS (depth, normals, ray counters): what a pass's tile classifier reads.
  void writeGBuffer(Context& ctx, DescriptorWrites& w, const GBufferDesc& g) const;
  // Writes the material bindings and picks the texture set: `materials` (null = the fallback, and the TLAS is
  // traced as opaque) and the TLAS's shading records. Sets RB_GB_ALPHA_TEST in `gbufferFlags` when the TLAS
  // holds non-opaque instances and a table is given; those need shading records (an error names `passName`).
  Status writeMaterials(DescriptorWrites& w, const TlasInfo& tlas, const MaterialTable* materials, const char* passName,
                        uint32_t& gbufferFlags);

  // Creates the outputs at width x height unless they exist at that size (a pass's prepare()); `passName` names
  // the pass in the error for an empty size.
  Status prepare(Context& ctx, uint32_t width, uint32_t height, const std::vector<PassImages::Spec>& outputs,
                 const char* passName);
  // Ensures the outputs, starts the measurements and makes the outputs writable.
  Status begin(Context& ctx, VkCommandBuffer cmd, const GBufferDesc& g, const std::vector<PassImages::Spec>& outputs);
  // Binds the pipeline (or `variant`, from createVariant()), set 0 (`w`), the texture set (when the pass has one)
  // and the push constants.
  void bind(Context& ctx, VkCommandBuffer cmd, const DescriptorWrites& w, const void* constants, uint32_t constantBytes,
            const RayTracingPipeline* variant = nullptr) const;
  // Traces one ray generation invocation per G-buffer pixel with the pass's push constants (ShadowConstants,
  // AoConstants, ...), then makes the outputs readable.
  template <typename Constants>
  void traceAndEnd(Context& ctx, VkCommandBuffer cmd, const DescriptorWrites& w, const Constants& pc,
                   const GBufferDesc& g, const RayTracingPipeline* variant = nullptr) {
    traceAndEnd(ctx, cmd, w, &pc, sizeof pc, g, variant);
  }
  void traceAndEnd(Context& ctx, VkCommandBuffer cmd, const DescriptorWrites& w, const void* constants,
                   uint32_t constantBytes, const GBufferDesc& g, const RayTracingPipeline* variant = nullptr);
  // Half resolution: one invocation per 2x2 block (ceil(w/2) x ceil(h/2), `half` ensured), tracing into `half`'s
  // samples, then the upsample into output 0, then end(): the pass's timestamps hold both. `roughnessThreshold`:
  // reflections' (the pixels that get no coverage).
  template <typename Constants>
  void traceHalfAndEnd(Context& ctx, VkCommandBuffer cmd, const DescriptorWrites& w, const Constants& pc,
                       const GBufferDesc& g, HalfResolution& half, float roughnessThreshold = 0.0f,
                       const RayTracingPipeline* variant = nullptr) {
    traceHalfAndEnd(ctx, cmd, w, &pc, sizeof pc, pc.gbuffer, g, half, roughnessThreshold, variant);
  }
  void traceHalfAndEnd(Context& ctx, VkCommandBuffer cmd, const DescriptorWrites& w, const void* constants,
                       uint32_t constantBytes, const GBufferConstants& traced, const GBufferDesc& g,
                       HalfResolution& half, float roughnessThreshold, const RayTracingPipeline* variant = nullptr);
  // The same with the launch size read from a VkTraceRaysIndirectCommandKHR on the GPU (a tile classifier's).
  template <typename Constants>
  void traceIndirectAndEnd(Context& ctx, VkCommandBuffer cmd, const DescriptorWrites& w, const Constants& pc,
                           VkDeviceAddress arguments, const RayTracingPipeline* variant = nullptr) {
    traceIndirect(ctx, cmd, w, pc, arguments, variant);
    end(ctx, cmd);
  }
  // Without the end: for a pass with work after its trace (images.endWrite(), that work, metrics.writeEnd()).
  template <typename Constants>
  void traceIndirect(Context& ctx, VkCommandBuffer cmd, const DescriptorWrites& w, const Constants& pc,
                     VkDeviceAddress arguments, const RayTracingPipeline* variant = nullptr) {
    bind(ctx, cmd, w, &pc, sizeof pc, variant);
    (variant ? *variant : pipeline).traceIndirect(ctx, cmd, arguments);
  }
  // Makes the outputs readable and ends the measurements.
  void end(Context& ctx, VkCommandBuffer cmd);
};

}  // namespace rb
