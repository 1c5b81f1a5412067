// Pure ray tracing: one primary ray per pixel from a pinhole camera (PrimaryRayCamera), shaded where it hits
// with the engine's materials exactly as reflection hits are (reflection_pass.h): base colour, metallic and
// emissive factors and textures, the sun with a shadow ray, the sky's ambient light, and the local lights of a
// LightList when given (one resampled light per hit, with its shadow ray). A ray that misses returns the sky.
// No G-buffer is read: the pass replaces an engine's rasterized shading (the thesis's "ray-traced" mode).
//
// Alpha: primary and shadow rays alpha-test non-opaque geometry with the material table (material_table.h):
// they pass through Mask cut-outs, and Blend surfaces stop them with probability alpha (per pixel and frame:
// stochastic transparency, since no forward pass draws blended surfaces afterwards).
//
// Needs: a TLAS built with TlasBuildOptions::writeShadingRecords, Instance::material set, a device whose ray
// recursion depth is at least 2 (a shadow ray from each hit). Outputs: radiance (RGBA16F, linear) and the
// distance from the eye to the hit along the unit ray direction (R32F, 0 = miss), in the pass's own images or
// the radiance in the caller's image (PrimaryShadingTargets::radiance).
//
// Lifetime: destroying it is safe while frames that recorded it are in flight: its pipeline, output images and
// measurement objects are handed to the Context's deferred release (see context.h) and freed once those frames
// are done. Destroy it before its Context.
//
// Thread safety: externally synchronised, like the Context it was created from.
#pragma once

#include <raybridge/acceleration_structures.h>
#include <raybridge/context.h>
#include <raybridge/effects.h>
#include <raybridge/light_list.h>
#include <raybridge/material_table.h>
#include <raybridge/primary_ray_pass.h>
#include <raybridge/reflection_pass.h>
#include <raybridge/scene_lighting.h>

#include <memory>

namespace rb {

// Defaults of PrimaryShadingSettings (the lighting's are SceneLighting's, shared with reflection hits).
inline constexpr uint32_t kDefaultPrimaryShadingLightCandidates = kDefaultReflectionLightCandidates;
inline constexpr uint32_t kMaxPrimaryShadingLightCandidates = 64;

// A zero-initialised PrimaryShadingSettings is valid: every zero field means the default named on its line.
struct PrimaryShadingSettings {
  SceneLighting lighting{};  // the sun with its shadow ray, what missing rays see, the sky light on hits
  // The table hits shade with and alpha-test with; nullptr = every surface white and opaque.
  const MaterialTable* materials = nullptr;
  // Local lights: this LightList, recorded earlier this frame for the same TLAS space. nullptr = sun and sky only.
  const LightList* lights = nullptr;
  uint32_t lightCandidates = 0;  // 0 = kDefaultPrimaryShadingLightCandidates; at most 64
};

struct PrimaryShadingTargets {
  uint32_t width = 0;   // required
  uint32_t height = 0;  // required
  // Optional: the caller's R16G16B16A16_SFLOAT storage image view, width x height, in VK_IMAGE_LAYOUT_GENERAL, to
  // write the radiance into instead of the pass's own image (e.g. the engine's HDR target). It stays in GENERAL;
  // the caller orders earlier accesses before VK_PIPELINE_STAGE_RAY_TRACING_SHADER_BIT_KHR and later reads after
  // it. VK_NULL_HANDLE = the pass's own image (PrimaryShadingOutputs::radiance).
  VkImageView radiance = VK_NULL_HANDLE;
};

// Fixed for the pass's life. Zero-initialised = images created at the first record().
struct PrimaryShadingPassDesc {
  // Create the output images at width x height now (as prepare()), so that outputs() names them and the first
  // record() allocates nothing; 0 x 0 = at the first record(). Both or neither.
  uint32_t width = 0, height = 0;
};

// What one record() traces. The TLAS and target size have no defaults: a zero-initialised frame is refused by name.
struct PrimaryShadingFrame {
  TlasInfo tlas{};            // recordTlasBuild()'s (with shading records), earlier in submission order
  PrimaryRayCamera camera{};  // world space
  PrimaryShadingTargets targets{};
  PrimaryShadingSettings settings{};
};

// Owned by the pass, left in SHADER_READ_ONLY_OPTIMAL after record().
struct PrimaryShadingOutputs {
  // R16G16B16A16_SFLOAT: rgb linear radiance towards the eye, a = 1. VK_NULL_HANDLE when the latest record()
  // wrote the caller's PrimaryShadingTargets::radiance instead.
  VkImage radiance = VK_NULL_HANDLE;
  VkImageView radianceView = VK_NULL_HANDLE;
  // R32_SFLOAT: distance from the eye to the hit along the pixel-centre ray (unit direction); 0 = nothing hit.
  VkImage distance = VK_NULL_HANDLE;
  VkImageView distanceView = VK_NULL_HANDLE;
  VkImageLayout layout = VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL;
  uint32_t width = 0, height = 0;
};

class PrimaryShadingPass {
 public:
  // Fails with ErrorCode::MissingFeature on a device whose ray recursion depth is below 2.
  static Result<std::unique_ptr<PrimaryShadingPass>> create(Context& context, const PrimaryShadingPassDesc& desc = {});
  // Retires its Vulkan objects to the context, without waiting: the images of outputs() stay valid for the
  // frames already recorded.
  ~PrimaryShadingPass();

  // Records the trace. The camera is in world space; the pass subtracts TlasInfo::originOffset from eye and target
  // (in double) to trace a camera-relative TLAS. The TLAS must have been built by recordTlasBuild() earlier in
  // submission order. On an error (named field) nothing is recorded.
  Status record(VkCommandBuffer cmd, const PrimaryShadingFrame& frame);
  // Creates the pass's own images (radiance and distance) at width x height now, so that outputs() names them before
  // the first record(); a record() at the same size that writes into its own radiance image keeps them, one at
  // another size or into the caller's radiance image recreates them. Written by the first record().
  Status prepare(uint32_t width, uint32_t height);
  const PrimaryShadingOutputs& outputs() const;
  // The latest measurement whose frame has finished: GPU time, and rays (primary plus shadow rays).
  PassStats stats() const;

  struct Impl;

 private:
  explicit PrimaryShadingPass(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace rb
