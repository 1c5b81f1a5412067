// Ray-traced ambient occlusion on the engine's G-buffer: n cosine-weighted rays over the hemisphere around
// the G-buffer normal, limited to a range. Output: the open fraction
//   AO(p) = (1/pi) * integral over the hemisphere of V_R(p, w) cos(theta) dw,   1 = fully open.
// Two estimators, as in the thesis: binary occlusion, and distance-weighted ("distance rays"), where a hit at
// distance t counts t / R open, so far occluders fade out.
//
// Half resolution (AoSettings::schedule.halfResolution): one ray generation invocation per 2x2 block of the G-buffer
// traces for one pixel of its block (the same corner in every block, a different one each frame: every pixel within 4
// frames, so a temporal denoiser sees them all) into an internal R16_SFLOAT image of ceil(w/2) x ceil(h/2) (half
// a byte per pixel, MemoryCategory::PassImages, held only while the setting is on). A compute pass then writes the
// full-resolution output from it: each pixel weights the samples around it bilinearly times their depth (distance
// from the pixel's tangent plane) and normal similarity, so occlusion does not bleed across silhouettes and
// creases; a pixel whose sample it is gets that sample exactly. The output keeps its format, size and layout.
// stats() then counts the rays actually traced (about a quarter) and its gpuMs covers the trace and the upsample.
//
// Converged tiles (AoSettings::schedule.convergedTiles, full resolution): as for soft shadows
// (raybridge/ray_schedule.h), tiles whose denoised AO history has converged trace no ray, and hold kept-history marks
// for the AO denoiser. A compute classifier over 8x8 tiles then lists the tiles that still need rays (any surface
// pixel, not converged) and the launch covers those alone (vkCmdTraceRaysIndirectKHR); all-sky tiles get their 1 from
// it. PassStats counts the tiles traced, skipped and converged, and the rays saved. The tile list and state take 16
// bytes + 8 bytes per tile (MemoryCategory::PassBuffers), held only while the setting is on.
//
// Lifetime: destroying it is safe while frames that recorded it are in flight: its pipeline, output image and
// measurement objects are handed to the Context's deferred release (see context.h) and freed once those
// frames are done. Destroy it before its Context.
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

enum class AoEstimator : uint8_t {
  Binary = 0,        // default: a hit within the range occludes; rays stop at the first hit
  DistanceWeighted,  // a hit at distance t counts t / range open; rays find the nearest hit
};

inline constexpr uint32_t kDefaultAoRays = 4;
inline constexpr float kDefaultAoRange = 1.0f;  // world units

struct AoSettings {
  uint32_t raysPerPixel = 0;  // 0 = kDefaultAoRays
  float range = 0.0f;         // world units; 0 = kDefaultAoRange. Use a large value (e.g. 1e6) for unlimited range.
  AoEstimator estimator = AoEstimator::Binary;
  // The materials that alpha-test non-opaque geometry (MaterialTable: Mask cut-outs, stochastic Blend), read
  // through the TLAS's shading records (needed then). nullptr = none: every surface occludes.
  const MaterialTable* materials = nullptr;
  // Where and how many rays (ray_schedule.h): adaptive rays (raysPerPixel is then the average the budget is made
  // of), half resolution (see Half resolution above) and converged tiles (their pixels hold kept-history marks
  // instead of AO, which schedule.history reads; full resolution only). Zero = every pixel traces its rays.
  RaySchedule schedule{};
};

// Fixed for the pass's life. Zero-initialised = images created at the first record().
struct AoPassDesc {
  // Create the output images at width x height now (as prepare()), so that outputs() names them and the first
  // record() allocates nothing; 0 x 0 = at the first record(). Both or neither.
  uint32_t width = 0, height = 0;
};

// What one record() traces. The G-buffer and TLAS have no defaults: a zero-initialised frame is refused by name.
struct AoFrame {
  GBufferDesc gbuffer{};  // the engine's G-buffer, its images in their declared layouts
  TlasInfo tlas{};        // from recordTlasBuild() earlier in submission order
  AoSettings settings{};
};

// Owned by the pass, sized to the G-buffer, left in SHADER_READ_ONLY_OPTIMAL after record().
struct AoOutputs {
  VkImage ao = VK_NULL_HANDLE;  // R16_SFLOAT open fraction; sky pixels are 1
  VkImageView aoView = VK_NULL_HANDLE;
  VkImageLayout layout = VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL;
  uint32_t width = 0, height = 0;
  // Adaptive rays (AoSettings::schedule.adaptive): the latest record()'s plan, R16G16_SFLOAT, .x = the rays the pixel
  // traced, .y = its reprojected history mean (a debug view of where rays went), in `layout`. VK_NULL_HANDLE when
  // that record() did not plan (adaptive rays off, or no history yet).
  VkImage rayPlan = VK_NULL_HANDLE;
  VkImageView rayPlanView = VK_NULL_HANDLE;
};

class AoPass {
 public:
  static Result<std::unique_ptr<AoPass>> create(Context& context, const AoPassDesc& desc = {});
  // Retires its Vulkan objects to the context, without waiting: the images of outputs() stay valid for
  // the frames already recorded.
  ~AoPass();

  // Records the AO rays of `frame` into `cmd`. On an error (named field) nothing is recorded.
  Status record(VkCommandBuffer cmd, const AoFrame& frame);
  // Creates the output images at width x height now, so that outputs() names them before the first record()
  // (HybridEffects hands out views that stay valid this way); record() at the same size keeps them, at another
  // size it recreates them. Written by the first record().
  Status prepare(uint32_t width, uint32_t height);
  const AoOutputs& outputs() const;
  PassStats stats() const;

  struct Impl;

 private:
  explicit AoPass(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace rb
