// Adaptive rays per pixel (by default planned per warp-sized tile) for the passes whose signal is a mean of many
// rays (AoPass, soft shadows of ShadowPass): rays go where the denoiser's reprojected history says the estimate is
// still uncertain, within a ray budget that can follow a GPU time budget from frame to frame.
//
// Each frame, before tracing, two compute dispatches plan the rays (sdk/src/adaptive_rays.h):
//   1. every pixel reprojects the history of the Denoiser that filters the pass's output (its running mean p over
//      f frames, as the denoiser's temporal pass will) and weighs itself by the variance its mean still has,
//      (p (1 - p) + 0.01) / f; a pixel without history counts as half a frame of p = 0.5;
//   2. every surface pixel gets minRaysPerPixel, the rest of the budget is shared in proportion to the weights
//      (rounded stochastically, at most maxRaysPerPixel), and a per-workgroup atomic claim guarantees that the
//      rays traced never exceed the budget. With Tile granularity (the default, below) the weights are summed per
//      tile and every surface pixel of a tile gets the tile's share of them.
// A pixel given no ray writes its reprojected history mean. The planning runs inside the pass's GPU timestamps:
// PassStats::gpuMs of an adaptive pass is planning plus tracing.
//
// Granularity (AdaptiveRaySettings::granularity). A ray generation launch runs neighbouring launch cells together,
// one warp of 32 lanes on NVIDIA, and a warp takes as long as its busiest lane: with a count per pixel the warp
// traces its maximum in every lane (measured: per-pixel adaptive AO had more error than uniform AO at equal GPU
// time, though less at equal rays; docs/performance.md, "Adaptive rays"). So by
// default the plan is per tile: step 2 shares the budget between tiles of tileWidth x tileHeight launch cells
// (aligned to multiples of the tile size) in proportion to the tile's summed weight, and gives every surface pixel
// of a tile the same count (sky pixels still 0); the claim under the budget also takes whole tiles, so a tile
// stays uniform even where the budget runs out. How a 2D vkCmdTraceRaysKHR launch is cut into warps is
// implementation-defined (OptiX only promises "tiles"; NVIDIA's ray generation warps are commonly 8x4 or 4x8
// cells, AMD's waves 32 or 64): the default 8x8 tile holds whole 8x4, 4x8 and 8x8 blocks, so it stays uniform per
// warp whichever of them the driver picks, at the cost of planning over 64 rather than 32 pixels. A launch cell
// is a pixel at full resolution and a 2x2 block at AoSettings::halfResolution (the planned tile is then twice as
// large in pixels); the shadow pass's tile classifier launches its 8x8 tiles row by row, which the tile sizes
// allowed here stay aligned with. Pixel granularity (one count per pixel) puts rays exactly where they are
// needed: the choice when rays, not time, are what is counted, or where divergence costs little (a CPU device).
// A real-time user pays in GPU time, hence the tile default; raybridge-effects-bench --scenario adaptive measures
// both (and 8x4, 4x8) at equal rays and equal time. With a time target, a tile plan's budget never falls below
// one ray in every pixel of one tile (the claim takes whole tiles).
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
// The most rays one adaptive frame plans, whatever maxRaysPerFrame, the time target or the uniform rays ask: 2^31,
// 64 rays per pixel at 8K, far past any frame's budget. The GPU claims rays with a 32-bit
// counter; under 2^31 it cannot wrap (a wrapped counter handed out rays again).
inline constexpr uint64_t kMaxAdaptiveRaysPerFrame = uint64_t(1) << 31;

// How finely the plan varies the rays (AdaptiveRaySettings::granularity).
enum class AdaptiveRayGranularity : uint32_t {
  Tile = 0,   // default: one count for every surface pixel of a tileWidth x tileHeight tile (warp-uniform tracing)
  Pixel = 1,  // one count per pixel: the finest placement, but a warp waits for its busiest pixel
};

// AdaptiveRaySettings::tileWidth and tileHeight when 0, in launch cells: 8x8 holds a whole warp whether the driver
// runs 8x4 or 4x8 launch cells per 32-lane warp (or 8x8 per 64-lane wave); see the header comment.
inline constexpr uint32_t kDefaultAdaptiveTileWidth = 8;
inline constexpr uint32_t kDefaultAdaptiveTileHeight = 8;
// The largest tile side, in launch cells (the planning workgroup holds one 16x16-pixel tile at half resolution).
inline constexpr uint32_t kMaxAdaptiveTileSize = 8;

struct AdaptiveRaySettings {
  bool enabled = false;  // false = raysPerPixel rays in every pixel (no planning, nothing allocated)
  // The Denoiser (DenoiseSignal::Scalar) that filters this pass's output, recorded after it each frame: its
  // history is the variance estimate. Required when enabled. HybridEffects sets it.
  const Denoiser* history = nullptr;
  // The pass's GPU time to aim for, in ms (planning and tracing). 0 = no time target. Needs timestamps on the
  // Context's queue family (DeviceInfo::timestampsSupported); the pass's record() fails with a named error
  // without them.
  float timeBudgetMs = 0.0f;
  // Most rays per frame, whatever the time target asks. 0 = no cap but maxRaysPerPixel per pixel and
  // kMaxAdaptiveRaysPerFrame (as is any larger value). Per tile, at least one ray in every pixel of one tile (the
  // claim takes whole tiles: less would trace nothing).
  uint64_t maxRaysPerFrame = 0;
  uint32_t minRaysPerPixel = 0;  // 0 = kDefaultAdaptiveMinRays
  uint32_t maxRaysPerPixel = 0;  // 0 = kDefaultAdaptiveMaxRaysFactor x raysPerPixel; at most kMaxAdaptiveRays
  AdaptiveRayGranularity granularity = AdaptiveRayGranularity::Tile;  // default: per tile (see the header comment)
  // The tile in launch cells (Tile granularity only): 0 = kDefaultAdaptiveTileWidth / kDefaultAdaptiveTileHeight;
  // otherwise a power of two at most kMaxAdaptiveTileSize. 8x4 or 4x8 plan more finely where the driver's warp
  // shape is known.
  uint32_t tileWidth = 0;
  uint32_t tileHeight = 0;
};

}  // namespace rb
