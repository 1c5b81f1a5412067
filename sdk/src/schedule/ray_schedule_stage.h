// The ray-scheduling stage (raybridge/ray_schedule.h): the one place that owns what decides where and how many rays
// an effect traces (the adaptive planner, the tile classifier and tile state, the converged-tile dispatches, the
// half-resolution image and upsample, the pipeline variants they need), creates and retires them, validates a
// RaySchedule, and wraps the effect's trace in one fixed sequence:
//   1. plan    adaptive rays from the denoiser's history (AdaptiveRayPlanner)
//   2. mark    converged tiles (ConvergedTiles::record)
//   3. classify the tiles that still need rays (TileClassifier), for Scalar signals
//   4. trace   over the tile list (indirect), over every pixel skipping converged tiles (RGB signals), at half
//              resolution, or over every pixel
//   5. finish  upsample (half resolution), check the refreshed converged tiles, end the pass's recording
// An effect describes itself once (ScheduledEffect: its signal, outputs, bindings, pipelines and the stages it
// allows), the way NRD's denoiser table describes each denoiser's inputs and outputs; its record() fills its own
// constants, calls prepare() before its recording begins and trace() after PassCore::begin().
#pragma once

#include <raybridge/denoiser.h>
#include <raybridge/ray_schedule.h>

#include <array>
#include <functional>
#include <string>
#include <vector>

#include "adaptive_rays.h"
#include "converged_tiles.h"
#include "half_resolution.h"
#include "pass_core.h"
#include "tile_classifier.h"

namespace rb {

// Which pipeline of an effect a launch uses: the bits of ScheduledEffect::pipelineDesc's argument.
enum ScheduleVariant : uint32_t {
  kVariantAdaptive = 1u << 0,  // reads the ray plan (RB_BINDING_RAY_PLAN)
  kVariantTiles = 1u << 1,     // reads the tile list (launch over tiles) or the tile state (launch that skips)
  kVariantReorder = 1u << 2,   // shader execution reordering (reflections)
  kVariantCount = 1u << 3,
};

inline constexpr uint32_t kNoConstant = UINT32_MAX;

// What an effect declares to the stage, once, at creation.
struct ScheduledEffect {
  const char* passName = "";                                       // names the pass in errors ("AoPass")
  uint32_t capabilities = 0;                                       // the RayScheduleCapability bits it allows
  DenoiseSignal signal = DenoiseSignal::Scalar;                    // the kind of denoiser its history comes from
  HalfResolution::Signal halfSignal = HalfResolution::Signal::Ao;  // with kScheduleHalfResolution
  uint32_t outputBinding = 0;               // the storage image the launch writes (half: the samples)
  uint32_t tileListBinding = kNoConstant;   // the classifier's list (Scalar signals)
  uint32_t tileStateBinding = kNoConstant;  // the tile state (the classifier's, or the skipping launch's)
  // Byte offsets in the push constants of the flags the stage sets (kNoConstant: the effect has none): 1 on a
  // frame whose converged tiles were marked, for the classifier; 1 while the launch covers the classifier's list.
  uint32_t convergedFlagOffset = kNoConstant;
  uint32_t launchOverTilesOffset = kNoConstant;
  // The classifier belongs to the effect (created with it, its list bound to every launch, as the shadow ray
  // generation shader statically reads it) rather than being made for converged tiles alone.
  bool classifierAlwaysBound = false;
  // The variant bits that make a pipeline of their own (others share the pass's), and that pipeline.
  uint32_t variantMask = 0;
  std::function<RayTracingPipelineDesc(uint32_t variant)> pipelineDesc;
  SpirvModule alphaAnyHit{};
  VkShaderStageFlags recordStages = 0;
  // The tile classifier (Scalar signals with kScheduleTileClassifier or kScheduleConvergedTiles).
  SpirvModule classifierShader{};
  // The bindings of the launch over the tile list (list binding included, material bindings not): the classifier
  // reads the same set but the TLAS, in a compute stage, plus the tile state.
  std::vector<VkDescriptorSetLayoutBinding> classifierLaunchBindings;
  uint32_t constantBytes = 0;
  const char* classifierName = "";
};

// The one validator of a RaySchedule: `field` names it in the error ("AoPass: AoSettings::schedule"), each
// message names the bad member after it and the fix. `historyFilled`: the caller sets RaySchedule::history itself
// (HybridEffects), so its absence is not an error. A stage outside `capabilities` is an error.
Status validateRaySchedule(const RaySchedule& schedule, uint32_t capabilities, DenoiseSignal signal,
                           const std::string& field, bool historyFilled = false);

// One frame of an effect's trace.
struct ScheduleFrame {
  const GBufferDesc& g;
  const RaySchedule& schedule;  // validated; the stages the frame runs (the effect may have turned some off)
  DescriptorWrites& w;          // the launch's set 0, with everything but the output and schedule bindings
  void* constants = nullptr;    // the push constants (the stage sets its flags in them)
  const GBufferConstants* traced = nullptr;  // their G-buffer part (the half-resolution upsample reads it)
  uint32_t raysPerPixel = 1;                 // the effect's uniform rays per pixel
  PassStats latest{};                        // the pass's latest finished measurement (the time target's feedback)
  float roughnessThreshold = 0.0f;           // reflections': pixels above it have no signal
  uint32_t variant = 0;                      // extra variant bits chosen by the effect (kVariantReorder)
  // Writes the effect's outputs the classifier reads and writes, besides the output binding (shadows: the hit
  // distance).
  std::function<void(DescriptorWrites&)> writeExtraOutputs;
};

class ScheduleStage {
 public:
  explicit ScheduleStage(ScheduledEffect effect);
  // Creates what the effect always holds (its classifier, when it belongs to it).
  Status init(Context& ctx);
  // Hands everything to the context's deferred release (frames in flight may still use it).
  void retire(Context& ctx);
  const ScheduledEffect& effect() const { return effect_; }

  // Creates the pipeline of `variant` now unless it exists (e.g. at the pass's creation).
  Status ensureVariant(Context& ctx, const PassCore& core, uint32_t variant);
  // Before the pass's recording begins (so that a failure records nothing): creates what this frame's schedule
  // needs and retires what it no longer uses.
  Status prepare(Context& ctx, const PassCore& core, const GBufferDesc& g, const RaySchedule& schedule,
                 uint32_t variant = 0);
  // Runs steps 1-5 (see the top) after core.begin() and the effect's own writes to f.w, ending the pass's
  // recording. On an error the recording is ended too. Returns whether the frame was planned (adaptive rays).
  Result<bool> trace(Context& ctx, PassCore& core, VkCommandBuffer cmd, ScheduleFrame& f);

  VkImage planImage() const { return planner_.planImage(); }
  VkImageView planView() const { return planner_.planView(); }

 private:
  const RayTracingPipeline* pipeline(uint32_t variant) const;
  void setConstant(void* constants, uint32_t offset, uint32_t value) const;
  bool classifierOn(const RaySchedule& s) const;
  void retireTiles(Context& ctx);
  Status initClassifier(Context& ctx);
  Result<bool> traceClassified(Context& ctx, PassCore& core, VkCommandBuffer cmd, ScheduleFrame& f, bool converged,
                               uint32_t variant);

  ScheduledEffect effect_;
  std::array<RayTracingPipeline, kVariantCount> variants_{};
  AdaptiveRayPlanner planner_;
  TileClassifier classifier_;
  bool classifierReady_ = false;
  ConvergedTiles converged_;
  HalfResolution half_;
};

}  // namespace rb
