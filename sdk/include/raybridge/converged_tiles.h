// Converged-tile skipping, for the passes whose denoised signal is a mean of rays (ShadowSettings::convergedTiles
// for soft shadows, AoSettings::convergedTiles for ambient occlusion, ReflectionSettings::convergedTiles for
// reflections, whose differences are in reflection_pass.h): a tile of 8x8 pixels whose every surface
// pixel has a reprojected history in the pass's denoiser of at least minFrames frames, with the noise the denoiser
// measured there under maxNoise, traces no ray. Its pixels are not a sample: they hold kept-history marks,
// -1 - (the reprojected history mean), in [-2, -1], which that denoiser's next record() reads as "no new frame":
// it carries the history to the pixel's new position unchanged (the reprojection, and its disocclusion test, are
// the denoiser's own, so a disoccluded pixel is never skipped). Read the denoised output, not the raw output, or
// decode a value v < -0.5 as -1 - v. A converged tile is still traced once in refreshPeriod frames (a rotating
// subset of the tiles each frame); when its new rays disagree with its history beyond their noise (a moved light or
// occluder, which the history cannot see) it is traced every frame for the next minFrames frames. Two compute
// dispatches over the tiles (before the pass's tile classifier and after the trace), within the pass's GPU time.
//
// Thread safety: plain data.
#pragma once

#include <cstdint>

namespace rb {

class Denoiser;

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
  bool enabled = false;  // true = skip converged tiles (turns the tile classifier on); needs `history`
  // The Denoiser that filters this pass's output (DenoiseSignal::Scalar for shadows and AO, Reflection for
  // reflections), recorded after it every frame (the same frame): its history decides, and its next record() reads
  // the marks. HybridEffects sets it.
  const Denoiser* history = nullptr;
  uint32_t minFrames = 0;  // frames of history a pixel needs; 0 = kDefaultConvergedMinFrames; at most 65535
  float maxNoise =
      0.0f;  // std. deviation of the denoiser's measured noise (reflections: relative, see above); 0 = default
  uint32_t refreshPeriod = 0;  // a converged tile is traced once in this many frames; 0 = the default, 1 = never skip
};

}  // namespace rb
