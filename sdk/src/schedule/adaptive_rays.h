// The planning half of adaptive rays (raybridge/ray_schedule.h): two compute dispatches that give every pixel its
// rays for this frame from the history of the pass's denoiser, within a ray budget (adaptive_estimate.comp, then
// adaptive_allocate.comp per pixel or adaptive_allocate_tiles.comp per tile), and the controller that moves the budget
// towards a GPU time target (adaptive_budget.h). A pass that supports adaptive rays owns one, and traces with its
// adaptive ray generation module, which reads the plan at RB_BINDING_RAY_PLAN. Owns two RG16F images at the G-buffer's
// size (MemoryCategory::PassImages) and a 16-byte counter buffer (PassBuffers), created on first use.
#pragma once

#include <raybridge/gbuffer.h>
#include <raybridge/ray_schedule.h>

#include "adaptive_budget.h"
#include "compute_pipeline.h"
#include "pass_images.h"

namespace rb {

struct PassCore;

class AdaptiveRayPlanner {
 public:
  // Hands the pipelines, images and counters to the context's deferred release.
  void retire(Context& ctx);

  // Records the planning for `g` and returns true, or returns false and records nothing when there is no history
  // to plan from yet (the denoiser has not recorded at this size): the pass then traces uniformly. `latest`: the
  // pass's latest finished measurement (the time target's feedback). `cellPixels`: the side in pixels of one
  // launch cell of the pass's trace (2 at half resolution), which scales the tiles of Tile granularity. After it,
  // plan() holds each pixel's rays and history mean in SHADER_READ_ONLY_OPTIMAL, visible to ray tracing, compute
  // and fragment shaders.
  Result<bool> record(Context& ctx, VkCommandBuffer cmd, const GBufferDesc& g, const AdaptiveRaySettings& settings,
                      const Denoiser* history, uint32_t raysPerPixel, const PassStats& latest, const char* who,
                      uint32_t cellPixels = 1);
  // What a pass does with it each frame, between its PassCore::begin() and its trace: record() when `settings` are
  // enabled, and bind the plan at RB_BINDING_RAY_PLAN of `w` with the pass's sampler. On an error the pass's
  // recording is ended (its outputs stay in a known layout; nothing is traced). Returns whether the frame was
  // planned: the pass then traces with its adaptive ray generation module.
  Result<bool> recordForPass(PassCore& core, Context& ctx, VkCommandBuffer cmd, const GBufferDesc& g,
                             const AdaptiveRaySettings& settings, const Denoiser* history, uint32_t raysPerPixel,
                             const PassStats& latest, const char* who, DescriptorWrites& w, uint32_t cellPixels = 1);
  VkImageView planView() const { return images_.size() > 1 ? images_[1].view : VK_NULL_HANDLE; }
  VkImage planImage() const { return images_.size() > 1 ? images_[1].image : VK_NULL_HANDLE; }
  // The ray budget of the latest record() (UINT32_MAX when it was the uniform rays, resolved on the GPU).
  uint64_t budget() const { return budget_; }

 private:
  // Creates the pipelines and counters that do not exist yet (of the allocation pipelines, the one `granularity`
  // uses).
  Status init(Context& ctx, AdaptiveRayGranularity granularity);
  ComputePipeline estimate_, allocate_, allocateTiles_;
  PassImages images_;  // 0: weights (mean, weight), 1: the plan (rays, mean)
  GpuBuffer counters_;
  RayBudgetController controller_;
  uint64_t budget_ = 0;
};

// The rays per pixel an adaptive pass may give one pixel (AdaptiveRaySettings::maxRaysPerPixel resolved).
uint32_t adaptiveMaxRays(const AdaptiveRaySettings& settings, uint32_t raysPerPixel);
// The tile of Tile granularity in launch cells (AdaptiveRaySettings::tileWidth and tileHeight resolved).
uint32_t adaptiveTileWidth(const AdaptiveRaySettings& settings);
uint32_t adaptiveTileHeight(const AdaptiveRaySettings& settings);

}  // namespace rb
