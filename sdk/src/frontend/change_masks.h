// The per-effect change masks of HybridEffects (shaders/change_masks.comp): R8_UNORM images, 1 where this frame's
// known changes (ChangeTracker's boxes, the engine's reactive mask) can have changed the effect's value. Each effect's
// pass and denoiser take the G-buffer with its reactive mask replaced by the effect's mask, so the denoiser, its
// converged tiles and adaptive rays all restart exactly those pixels (denoiser.h, ray_schedule.h). Frames without a
// known change record nothing and leave the G-buffer as the engine gave it. The images exist from the first frame
// that could need them (change resets on, the effect denoised), at the G-buffer's size: 1 byte a pixel each; a change
// then allocates nothing, so memory stays flat however rarely changes come.
//
// Thread safety: none; owned by one HybridEffects, used by its record().
#pragma once

#include <raybridge/effects.h>
#include <raybridge/gbuffer.h>

#include <span>

#include "change_tracker.h"
#include "compute_pipeline.h"
#include "gpu_memory.h"
#include "pass_metrics.h"

namespace rb {

// What the masks need of the frame besides the boxes.
struct ChangeMaskInputs {
  uint32_t masks = 0;    // RB_CHANGE_* bits: the effects to write a mask for
  Light shadowLight{};   // the light the shadow effect traces (its rays cross a moved object's old and new box)
  float aoRange = 0.0f;  // AoSettings::range resolved
};

class ChangeMasks {
 public:
  // Records this frame's masks, or nothing (returns false) when `boxes` is empty: then gbufferFor() gives the
  // engine's G-buffer unchanged. Creates what the masks of in.masks need first, changes or not. Errors (an image or
  // buffer that could not be created) record nothing.
  Result<bool> record(Context& ctx, VkCommandBuffer cmd, const GBufferDesc& g, const TlasInfo& tlas,
                      std::span<const GpuChangeBox> boxes, const ChangeMaskInputs& in);
  // Creates the pipeline, box ring, sampler, timer and the images of `masks` (RB_CHANGE_* bits) at width x height,
  // and retires the images of other masks or another size. record() calls it too.
  Status prepare(Context& ctx, uint32_t masks, uint32_t width, uint32_t height);
  // `g` with its reactive mask replaced by the mask of `effect` (one RB_CHANGE_* bit) when the latest record()
  // wrote one, else `g`.
  GBufferDesc gbufferFor(const GBufferDesc& g, uint32_t effect) const;
  // The mask of `effect` the latest record() wrote (a debug view's readback), or nullptr.
  const GpuImage* mask(uint32_t effect) const;
  // Forget the latest record(): gbufferFor() gives the engine's G-buffer until the next record() with changes.
  void clear() { written_ = 0; }
  void retire(Context& ctx);  // to the deferred release
  // GPU time of the latest frame that recorded masks (0 before the first).
  PassStats stats(Context& ctx) { return metricsReady_ ? metrics_.latest(ctx) : PassStats{}; }

 private:
  static int slotOf(uint32_t effect);
  GpuImage images_[4];  // RB_CHANGE_SHADOWS, AO, LOCAL_LIGHTS, REFLECTIONS
  GpuBuffer ring_;      // host-visible: kMaxChangeBoxes boxes per frame in flight
  ComputePipeline pipeline_;
  VkSampler sampler_ = VK_NULL_HANDLE;  // nearest: the depth and reactive mask are read with texelFetch
  PassMetrics metrics_;
  bool metricsReady_ = false;
  uint32_t written_ = 0;  // RB_CHANGE_* bits of the masks the latest record() wrote
};

}  // namespace rb
