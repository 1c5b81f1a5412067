// Where and how many rays an effect traces: one description, RaySchedule, that every ray-traced effect takes
// (ShadowSettings::schedule, AoSettings::schedule, ReflectionSettings::schedule, ManyLightSettings::schedule, and
// the same fields of HybridEffectsDesc's effect settings). It is validated once, against the effect's denoiser, and
// one internal stage runs it for every effect, in one fixed sequence:
//   1. plan rays (adaptive rays: from the denoiser's history),
//   2. mark converged tiles (their pixels hold kept-history marks and trace nothing),
//   3. classify tiles (list the 8x8 tiles that still need rays),
//   4. trace: over the tile list (indirect), over every pixel skipping converged tiles, at half resolution, or over
//      every pixel; resetRays rays where the reactive mask restarts a pixel's history,
//   5. upsample (half resolution) and check the refreshed converged tiles.
// A stage an effect does not allow is an error that names the field (kScheduleCapabilities below lists them).
//
// Thread safety: plain data.
//
// ---- Adaptive rays (RaySchedule::adaptive) ----
//
// Adaptive rays per pixel (by default planned per warp-sized tile) for the passes whose signal is a mean of many
// rays (AoPass, soft shadows of ShadowPass): rays go where the denoiser's reprojected history says the estimate is
// still uncertain, within a ray budget that can follow a GPU time budget from frame to frame.
//
// Each frame, before tracing, two compute dispatches plan the rays (sdk/src/schedule/adaptive_rays.h):
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
// Granularity (RaySchedule::adaptive.granularity). A ray generation launch runs neighbouring launch cells together,
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
// is a pixel at full resolution and a 2x2 block at RaySchedule::halfResolution (the planned tile is then twice as
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
//
// ---- Converged tiles (RaySchedule::convergedTiles) ----
//
// Converged-tile skipping, for the passes whose denoised signal is a mean of rays
// (ShadowSettings::schedule.convergedTiles for soft shadows, AoSettings::schedule.convergedTiles for ambient occlusion,
// ReflectionSettings::schedule.convergedTiles for reflections, whose differences are in reflection_pass.h): a tile of
// 8x8 pixels whose every surface pixel has a reprojected history in the pass's denoiser of at least minFrames frames,
// with the noise the denoiser measured there under maxNoise, traces no ray. Its pixels are not a sample: they hold
// kept-history marks, -1 - (the reprojected history mean), in [-2, -1], which that denoiser's next record() reads as
// "no new frame": it carries the history to the pixel's new position unchanged (the reprojection, and its disocclusion
// test, are the denoiser's own, so a disoccluded pixel is never skipped). Read the denoised output, not the raw output,
// or decode a value v < -0.5 as -1 - v. A converged tile is still traced once in refreshPeriod frames (a rotating
// subset of the tiles each frame); when its new rays disagree with its history beyond their noise (a moved light or
// occluder, which the history cannot see) it is traced every frame for the next minFrames frames. Two compute
// dispatches over the tiles (before the pass's tile classifier and after the trace), within the pass's GPU time.
//
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

// How finely the plan varies the rays (RaySchedule::adaptive.granularity).
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
  bool enabled =
      false;  // false = raysPerPixel rays in every pixel (no planning, nothing allocated); needs RaySchedule::history
  // The pass's GPU time to aim for, in ms (planning and tracing). 0 = no time target. Needs timestamps on the
  // Context's queue family (DeviceInfo::timestampsSupported); the pass's record() fails with a named error
  // without them.
  float timeBudgetMs = 0.0f;
  // Most rays per frame, whatever the time target asks. 0 = no cap but maxRaysPerPixel per pixel and
  // kMaxAdaptiveRaysPerFrame (as is any larger value). Per tile, at least one ray in every pixel of one tile (the
  // claim takes whole tiles: less would trace nothing).
  uint64_t maxRaysPerFrame = 0;
  // With a time target: where the budget starts, in rays per pixel of the image. 0 = raysPerPixel (the uniform
  // pass's rays). Low values start cheap and climb to the target (at most 2x a measurement): what a frame budget
  // (HybridEffectsDesc::budgetMs) asks for, so that the first frames do not run over it.
  float initialRaysPerPixel = 0.0f;
  uint32_t minRaysPerPixel = 0;  // 0 = kDefaultAdaptiveMinRays
  uint32_t maxRaysPerPixel = 0;  // 0 = kDefaultAdaptiveMaxRaysFactor x raysPerPixel; at most kMaxAdaptiveRays
  AdaptiveRayGranularity granularity = AdaptiveRayGranularity::Tile;  // default: per tile (see the header comment)
  // The tile in launch cells (Tile granularity only): 0 = kDefaultAdaptiveTileWidth / kDefaultAdaptiveTileHeight;
  // otherwise a power of two at most kMaxAdaptiveTileSize. 8x4 or 4x8 plan more finely where the driver's warp
  // shape is known.
  uint32_t tileWidth = 0;
  uint32_t tileHeight = 0;
};


// Defaults of ConvergedTileSettings: a tile is converged when each of its surface pixels has a history of at least
// 16 frames (half the denoiser's default 32) whose measured noise has a standard deviation under 0.05 (half
// kDefaultDenoiseConvergedNoise: 4 rays at visibility 0.5 need 25 frames), and it is still traced once in 8 frames.
// For reflections, whose signal is a colour of any brightness, maxNoise is relative: the standard deviation of the
// mean over the mean colour's length (at least 0.05), so 0.05 = 5% noise.
inline constexpr uint32_t kDefaultConvergedMinFrames = 16;
inline constexpr float kDefaultConvergedMaxNoise = 0.05f;
inline constexpr uint32_t kDefaultConvergedRefreshPeriod = 8;

// Skipping the tiles whose denoised history has converged (see the top of this file). Zero-initialised = off, and
// the defaults when enabled.
struct ConvergedTileSettings {
  bool enabled = false;    // true = skip converged tiles; needs RaySchedule::history
  uint32_t minFrames = 0;  // frames of history a pixel needs; 0 = kDefaultConvergedMinFrames; at most 65535
  float maxNoise =
      0.0f;  // std. deviation of the denoiser's measured noise (reflections: relative, see above); 0 = default
  uint32_t refreshPeriod = 0;  // a converged tile is traced once in this many frames; 0 = the default, 1 = never skip
};

// The stages of a RaySchedule (RayScheduleCapability bits). Which effect allows which:
//   shadows (ShadowPass, soft lights):     adaptive rays, converged tiles, the tile classifier, reset rays
//   ambient occlusion (AoPass):            adaptive rays, converged tiles, half resolution, reset rays
//   reflections (ReflectionPass):          converged tiles, half resolution
//   local lights (ManyLightPass, Stochastic): converged tiles
// Converged tiles and half resolution exclude each other (tiles are of full-resolution pixels).
enum RayScheduleCapability : uint32_t {
  kScheduleAdaptiveRays = 1u << 0,
  kScheduleConvergedTiles = 1u << 1,
  kScheduleHalfResolution = 1u << 2,
  kScheduleTileClassifier = 1u << 3,
  kScheduleResetRays = 1u << 4,
};
inline constexpr uint32_t kShadowScheduleCapabilities = kScheduleAdaptiveRays | kScheduleConvergedTiles |
                                                        kScheduleTileClassifier | kScheduleResetRays;
inline constexpr uint32_t kAoScheduleCapabilities = kScheduleAdaptiveRays | kScheduleConvergedTiles |
                                                    kScheduleHalfResolution | kScheduleResetRays;
inline constexpr uint32_t kReflectionScheduleCapabilities = kScheduleConvergedTiles | kScheduleHalfResolution;
inline constexpr uint32_t kLocalLightScheduleCapabilities = kScheduleConvergedTiles;

// Where and how many rays an effect traces (see the top of this file). Zero-initialised = every pixel traces the
// effect's own rays per pixel at full resolution, nothing planned, classified or skipped, nothing allocated.
struct RaySchedule {
  // The Denoiser that filters the effect's output (DenoiseSignal::Scalar for shadows and AO, Reflection for
  // reflections, Rgb for local lights), recorded after the effect each frame: adaptive rays plan from its history,
  // converged tiles read it and its next record() reads their marks. Required by either; HybridEffects sets it to
  // the effect's own denoiser (a value given there is ignored).
  const Denoiser* history = nullptr;
  // Rays per pixel where the history says the estimate is uncertain, within a budget; the effect's raysPerPixel is
  // then the average the budget is made of. Off by default.
  AdaptiveRaySettings adaptive{};
  // Skip the 8x8-pixel tiles whose denoised history has converged (see above). Full resolution only. With the tile
  // classifier (shadows, AO) the launch covers the remaining tiles alone; reflections and local lights skip inside
  // their launch. Off by default.
  ConvergedTileSettings convergedTiles{};
  // Trace one pixel per 2x2 block (a different one each frame, every pixel within 4 frames) into a half-size image,
  // then upsample it to the output by depth and normal similarity: about a quarter of the rays. false = every pixel.
  bool halfResolution = false;
  // Shadows: a compute pass over 8x8 tiles first writes the tiles where no pixel needs a ray (sky, back-facing) and
  // the launch covers the others alone (vkCmdTraceRaysIndirectKHR). Converged tiles turn it on. false = off (see
  // shadow_pass.h for when it pays).
  bool tileClassifier = false;
  // Rays per pixel where the pixel's history restarts this frame: where the G-buffer's reactive mask is set (.r >
  // 0.5; HybridEffects replaces it with the effect's change mask: the pixels a moved object, light or the engine's own
  // mask changed). A restarted pixel otherwise holds one frame of raysPerPixel rays beside neighbours that hold
  // maxHistoryFrames of them, and stays several times their error for as many frames as it takes to catch up
  // (docs/effects.md, "Reset rays"). Tell the Denoiser: DenoiseSettings::resetFrames = resetRays / raysPerPixel, so
  // that its running mean weighs this frame's value by its rays. Costs resetRays - raysPerPixel extra rays in each
  // changed pixel, nothing elsewhere. Also traced where the mask is above 0.25 and at most 0.5 (a follow-up of a
  // restart: GBufferDesc::reactiveMask). 0 (or at most raysPerPixel) = off. At most kMaxRaysPerPixel. Not with adaptive
  // rays (they already plan the most rays where a history restarts) nor halfResolution; soft shadows only.
  uint32_t resetRays = 0;
};

}  // namespace rb
