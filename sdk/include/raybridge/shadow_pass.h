// Ray-traced shadows on the engine's G-buffer: hard (one ray) and soft (several rays over the light's disk)
// for directional, point and spot lights. Outputs sun/light visibility in [0, 1] and, when asked for, the
// distance to the nearest occluder.
//
// Traces nothing for sky pixels, surfaces whose normal faces away from the light, or pixels outside a spot
// cone or light range. Ray origins are offset along the geometric normal by the depth buffer's
// reconstruction error, so grazing light does not cause acne.
//
// A tile classifier (ShadowSettings::schedule.tileClassifier) can run that same per-pixel test first, in a compute pass
// over 8x8-pixel tiles: tiles where no pixel needs a ray get their outputs from it, and only the others are
// traced (vkCmdTraceRaysIndirectKHR). The outputs are the same bit for bit either way; PassStats counts the tiles
// traced and skipped. It is off by default: where measured the pass was slower with it (docs/performance.md),
// since the pixels it skips already end before their first ray. Its tile list takes 16
// bytes + 8 bytes per tile (the list and the converged-tile state; MemoryCategory::PassBuffers, about 260 KB at
// 1920x1080), allocated with the output images.
//
// Converged tiles (ShadowSettings::schedule.convergedTiles, with the classifier): for denoised shadows, a tile whose
// every surface pixel has a reprojected history in the shadow denoiser of at least minFrames frames, with the noise the
// denoiser measured there under maxNoise, traces no ray. Its pixels are not a sample: they hold kept-history marks,
// -1 - (the reprojected history mean), in [-2, -1], which that denoiser's next record() reads as "no new frame":
// it carries the history to the pixel's new position unchanged (the reprojection, and its disocclusion test, are
// the denoiser's own, so a disoccluded pixel is never skipped). Read the denoised output, not the raw visibility,
// or decode a value v < -0.5 as -1 - v. A converged tile is still traced once in refreshPeriod frames (a rotating
// subset of the tiles each frame); when its new rays disagree with its history beyond their noise (a moved light or
// occluder, which the history cannot see) it is traced every frame for the next minFrames frames. Two compute
// dispatches over the tiles (before the classifier and after the trace), within the pass's GPU time.
//
// Lifetime: destroying it is safe while frames that recorded it are in flight: its pipelines, output images,
// tile list and measurement objects are handed to the Context's deferred release (see context.h) and freed once
// those frames are done. Destroy it before its Context.
//
// Thread safety: externally synchronised, like the Context it was created from.
#pragma once

#include <raybridge/acceleration_structures.h>
#include <raybridge/effects.h>
#include <raybridge/gbuffer.h>
#include <raybridge/material_table.h>
#include <raybridge/ray_schedule.h>

#include <memory>

namespace rb {

// Fixed for the pass's life. Zero-initialised = visibility only, images created at the first record().
struct ShadowPassDesc {
  // Allocate and write the occluder-distance image (for denoisers and contact hardening). false = the
  // visibility image only, and rays stop at the first occluder they find.
  bool outputHitDistance = false;
  // Create the output images at width x height now (as prepare()), so that outputs() names them and the first
  // record() allocates nothing; 0 x 0 = at the first record(). Both or neither.
  uint32_t width = 0, height = 0;
};

inline constexpr uint32_t kDefaultSoftShadowRays = 4;

struct ShadowSettings {
  // Rays per pixel for a soft light (angular radius or radius > 0); 0 = kDefaultSoftShadowRays. A hard light
  // always uses one.
  uint32_t raysPerPixel = 0;
  // The materials that alpha-test non-opaque geometry (MaterialTable: Mask cut-outs, stochastic Blend), read
  // through the TLAS's shading records (needed then). nullptr = none: every surface casts a solid shadow.
  const MaterialTable* materials = nullptr;
  // Where and how many rays (ray_schedule.h): the tile classifier (schedule.tileClassifier: classify 8x8 tiles
  // first and trace only those with a pixel that needs a ray; off by default, faster where skipped pixels are
  // cheap, see the top of this file), and for soft lights adaptive rays (a hard light traces one ray per pixel
  // regardless) and converged tiles (which turn the classifier on). Adaptive rays and converged tiles are not
  // available with ShadowPassDesc::outputHitDistance (a skipped or planned pixel has no occluder distance).
  RaySchedule schedule{};
};

// Images owned by the pass, sized to the G-buffer, left in VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL after
// record() with a barrier that makes them readable by fragment and compute shaders.
struct ShadowOutputs {
  // R16_SFLOAT, 1 = lit; with ShadowSettings::schedule.convergedTiles, skipped pixels hold kept-history marks (see the
  // top).
  VkImage visibility = VK_NULL_HANDLE;
  VkImageView visibilityView = VK_NULL_HANDLE;
  VkImage hitDistance = VK_NULL_HANDLE;  // R32_SFLOAT, world units; 0 = no occluder; only with outputHitDistance
  VkImageView hitDistanceView = VK_NULL_HANDLE;
  VkImageLayout layout = VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL;
  uint32_t width = 0, height = 0;
  // Adaptive rays (ShadowSettings::schedule.adaptive): the latest record()'s plan, as AoOutputs::rayPlan (.x rays per
  // pixel, .y reprojected history mean). VK_NULL_HANDLE when that record() did not plan.
  VkImage rayPlan = VK_NULL_HANDLE;
  VkImageView rayPlanView = VK_NULL_HANDLE;
};

// What one record() traces. The G-buffer and TLAS have no defaults: a zero-initialised frame is refused by name.
struct ShadowFrame {
  GBufferDesc gbuffer{};  // the engine's G-buffer, its images in their declared layouts
  // From recordTlasBuild() earlier in submission order (ideally with originOffset = the camera position).
  TlasInfo tlas{};
  Light light{};  // checked by the one rb::Light validator (light_validation: the same limits for every pass)
  ShadowSettings settings{};
};

class ShadowPass {
 public:
  static Result<std::unique_ptr<ShadowPass>> create(Context& context, const ShadowPassDesc& desc = {});
  // Retires its Vulkan objects to the context, without waiting: the images of outputs() stay valid for
  // the frames already recorded.
  ~ShadowPass();

  // Records the shadow rays of `frame` into `cmd`. On an error (named field) nothing is recorded.
  Status record(VkCommandBuffer cmd, const ShadowFrame& frame);
  // Creates the output images at width x height now, so that outputs() names them before the first record()
  // (HybridEffects hands out views that stay valid this way); record() at the same size keeps them, at another
  // size it recreates them. Written by the first record().
  Status prepare(uint32_t width, uint32_t height);
  const ShadowOutputs& outputs() const;
  // GPU time (classifier included), rays and classified tiles of the latest recording whose frame has finished.
  PassStats stats() const;

  struct Impl;

 private:
  explicit ShadowPass(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace rb
