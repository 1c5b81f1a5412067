// Adaptive rays per pixel for the passes whose signal is a mean of many rays (AoPass, soft shadows of ShadowPass):
// rays go where the denoiser's reprojected history says the estimate is still uncertain, within a ray budget that
// can follow a GPU time budget from frame to frame.
//
// Each frame, before tracing, two compute dispatches plan the rays (sdk/src/adaptive_rays.h):
//   1. every pixel reprojects the history of the Denoiser that filters the pass's output (its running mean p over
//      f frames, as the denoiser's temporal pass will) and weighs itself by the variance its mean still has,
//      (p (1 - p) + 0.01) / f; a pixel without history counts as half a frame of p = 0.5;
//   2. every surface pixel gets minRaysPerPixel, the rest of the budget is shared in proportion to the weights
//      (rounded stochastically, at most maxRaysPerPixel), and a per-workgroup atomic claim guarantees that the
//      rays traced never exceed the budget.
// A pixel given no ray writes its reprojected history mean. The planning runs inside the pass's GPU timestamps:
// PassStats::gpuMs of an adaptive pass is planning plus tracing.
//
// The budget: maxRaysPerFrame when timeBudgetMs is 0 and it is set; else the uniform pass's rays (raysPerPixel per
// surface pixel) redistributed; with timeBudgetMs the pass measures its own GPU time on finished frames and moves
// the budget towards it (proportionally, damped), never above maxRaysPerFrame.
//
// The first frame, and a frame whose denoiser has no images of the G-buffer's size yet, trace uniformly: there is
// no history to plan from. Memory: two RG16F images and 16 bytes of counters, allocated on first use.
//
// Thread safety: plain data.
#pragma once

#include <cstdint>

namespace rb {

class Denoiser;

// Default of AdaptiveRaySettings::minRaysPerPixel: one ray everywhere keeps every pixel's estimate fresh (a pixel
// given none repeats its history).
inline constexpr uint32_t kDefaultAdaptiveMinRays = 1;
// AdaptiveRaySettings::maxRaysPerPixel when 0: four times the pass's raysPerPixel, at most kMaxAdaptiveRays.
inline constexpr uint32_t kDefaultAdaptiveMaxRaysFactor = 4;
inline constexpr uint32_t kMaxAdaptiveRays = 256;

struct AdaptiveRaySettings {
  bool enabled = false;  // false = raysPerPixel rays in every pixel (no planning, nothing allocated)
  // The Denoiser (DenoiseSignal::Scalar) that filters this pass's output, recorded after it each frame: its
  // history is the variance estimate. Required when enabled. HybridEffects sets it.
  const Denoiser* history = nullptr;
  // The pass's GPU time to aim for, in ms (planning and tracing). 0 = no time target.
  float timeBudgetMs = 0.0f;
  // Most rays per frame, whatever the time target asks. 0 = no cap but maxRaysPerPixel per pixel.
  uint64_t maxRaysPerFrame = 0;
  uint32_t minRaysPerPixel = 0;  // 0 = kDefaultAdaptiveMinRays
  uint32_t maxRaysPerPixel = 0;  // 0 = kDefaultAdaptiveMaxRaysFactor x raysPerPixel; at most kMaxAdaptiveRays
};

}  // namespace rb
