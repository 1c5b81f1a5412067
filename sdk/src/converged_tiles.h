// Converged-tile skipping (raybridge/converged_tiles.h) for the shadow pass (ShadowSettings::convergedTiles) and the
// AO pass (AoSettings::convergedTiles): the two compute dispatches around the pass's tile classifier that decide,
// from its denoiser's history, which tiles have converged and write their kept-history marks into the pass's R16F
// output (shadow_converged.comp), and after the trace check the refreshed tiles for a change the history could not
// see (shadow_converged_check.comp). Both signals are in [0, 1] with sky at 1, so the shaders serve both. The tile
// state they share lives in the TileClassifier. Owns the two pipelines, created on first use.
#pragma once

#include <raybridge/converged_tiles.h>
#include <raybridge/gbuffer.h>

#include "compute_pipeline.h"
#include "denoiser_history.h"
#include "pass_constants.h"

namespace rb {

class TileClassifier;

class ConvergedTiles {
 public:
  // Checks the settings; `who` names the pass and field in the error ("ShadowPass: ShadowSettings::convergedTiles").
  static Status validate(const ConvergedTileSettings& settings, const char* who);
  void retire(Context& ctx);

  // Records step 1 for `g` and returns true, or returns false and records nothing when the denoiser has no history
  // of this size yet (nothing is converged). `visibility`: the pass's output, writable by compute shaders. After it,
  // the tile state and the skipped tiles' outputs are visible to the classifier. `raysPerPixel`: the pass's uniform
  // rays (the check's noise model). Tells the denoiser that its next record() this frame reads marks.
  Result<bool> record(Context& ctx, VkCommandBuffer cmd, const GBufferDesc& g, const ConvergedTileSettings& settings,
                      uint32_t raysPerPixel, TileClassifier& classifier, VkImageView visibility, const char* who);
  // Records step 2, after the trace, once the pass's outputs are readable by compute shaders (only after a record()
  // that returned true, in the same frame).
  void check(Context& ctx, VkCommandBuffer cmd, const GBufferDesc& g, const TileClassifier& classifier,
             VkImageView visibility) const;

 private:
  Status init(Context& ctx, const char* who);
  // The bindings both dispatches share, from the latest record().
  void writeCommon(DescriptorWrites& w, const GBufferDesc& g, const TileClassifier& classifier) const;
  ComputePipeline mark_, check_;
  ConvergedTileConstants constants_{};
  internal::DenoiserHistory history_;
  uint32_t recordings_ = 0;  // record()s that found history: the refresh rotation
};

}  // namespace rb
