// Converged-tile skipping (raybridge/ray_schedule.h) for the shadow pass (ShadowSettings::schedule.convergedTiles), the
// AO pass (AoSettings::schedule.convergedTiles), the reflection pass (ReflectionSettings::schedule.convergedTiles) and
// the many-light pass (ManyLightSettings::schedule.convergedTiles): the two compute dispatches around the pass's trace
// that decide, from its denoiser's history, which tiles have converged and write their kept-history marks into the
// pass's output, and after the trace check the refreshed tiles for a change the history could not see. Shadows and AO
// (a Scalar denoiser): shadow_converged.comp and shadow_converged_check.comp, which serve both, as both signals are in
// [0, 1] with sky at 1, around the pass's tile classifier. Reflections and local lights (a Reflection or Rgb denoiser):
// rgb_converged.comp and rgb_converged_check.comp, which for reflections also follow how far the view turned, and
// which count the pass's tiles (those passes have no classifier: their ray generation shader skips the converged
// tiles). The tile state lives in the TileClassifier. Owns the two pipelines, created on first use.
#pragma once

#include <raybridge/denoiser.h>
#include <raybridge/gbuffer.h>
#include <raybridge/ray_schedule.h>

#include "compute_pipeline.h"
#include "denoiser_history.h"
#include "pass_constants.h"

namespace rb {

struct PassCore;
class TileClassifier;

class ConvergedTiles {
 public:
  // `signal`: the kind of Denoiser whose history it reads: Scalar (shadows, AO), Reflection or Rgb (local lights).
  explicit ConvergedTiles(DenoiseSignal signal = DenoiseSignal::Scalar) : signal_(signal) {}
  void retire(Context& ctx);

  // Records step 1 for `g` and returns true, or returns false and records nothing when the denoiser has no history
  // of this size yet (nothing is converged). `visibility`: the pass's output, writable by compute shaders. After it,
  // the tile state and the skipped tiles' outputs are visible to the classifier. `raysPerPixel`: the pass's uniform
  // rays (the check's noise model for shadows and AO; the rays saved for RGB signals). Tells the denoiser that its
  // next record() this frame reads marks. Reflections: `roughnessThreshold`, the pass's (rougher pixels have no
  // reflection). RGB signals: `counters`, the pass's ray counters (this dispatch counts the tiles and the rays
  // saved); the tile state is then visible to ray tracing shaders too.
  Result<bool> record(Context& ctx, VkCommandBuffer cmd, const GBufferDesc& g, const ConvergedTileSettings& settings,
                      const Denoiser* history, uint32_t raysPerPixel, TileClassifier& classifier,
                      VkImageView visibility, const char* who, float roughnessThreshold = 0.0f,
                      VkDescriptorBufferInfo counters = {});
  // Records step 2, after the trace (only after a record() that returned true, in the same frame): for shadows and
  // AO once the pass's outputs are readable by compute shaders (after endWrite()); for RGB signals while the
  // output is still in GENERAL (before endWrite(), which must then cover compute writes), as the check marks the
  // held tiles' pixels stale in it.
  void check(Context& ctx, VkCommandBuffer cmd, const GBufferDesc& g, const TileClassifier& classifier,
             VkImageView visibility) const;
  // RGB signals, whose launch skips the converged tiles itself (reflections, local lights), after the pass's
  // core.begin(): record() into the pass's output 0 with its ray counters and, when it found history, the launch
  // over every pixel with `skipping` (whose ray generation shader reads the tile state at `stateBinding`, added to
  // `w`), the check and the end of the pass's recording; returns true then. Returns false, having recorded nothing,
  // when there is no history yet: the pass traces as usual. On an error the pass's recording is ended.
  Result<bool> traceSkipping(PassCore& core, Context& ctx, VkCommandBuffer cmd, const GBufferDesc& g,
                             const ConvergedTileSettings& settings, const Denoiser* history, uint32_t raysPerPixel,
                             TileClassifier& state, DescriptorWrites& w, const void* constants, uint32_t constantBytes,
                             const RayTracingPipeline& skipping, uint32_t stateBinding, const char* who,
                             float roughnessThreshold = 0.0f);

 private:
  Status init(Context& ctx, const char* who);
  // The bindings both dispatches share, from the latest record().
  void writeCommon(DescriptorWrites& w, const GBufferDesc& g, const TileClassifier& classifier) const;
  DenoiseSignal signal_;
  ComputePipeline mark_, check_;
  ConvergedTileConstants constants_{};
  DenoiseHistory history_;
  uint32_t recordings_ = 0;  // record()s that found history: the refresh rotation
};

}  // namespace rb
