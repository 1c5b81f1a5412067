// What the motion scenario measures on captured frames: error over a pixel set, the pixels whose converged value
// changed, the newly visible pixels, and flicker (see docs/effects.md, "Motion"). Plain functions on host images.
#pragma once

#include <cstdint>
#include <vector>

#include <glm/glm.hpp>

namespace rbEffects {

// One effect's image of one frame: `channels` floats per pixel (RGB effects are compared on rgb: 3).
struct EffectFrame {
  std::vector<float> values;
  uint32_t channels = 1;
};

// RMSE over the pixels set in `pixels` and every channel; 0 when none is set.
double rmseOver(const EffectFrame& test, const EffectFrame& reference, const std::vector<uint8_t>& pixels);
// Mean over the pixels set in `pixels` of the channels' mean absolute difference between two frames.
double meanAbsoluteChange(const EffectFrame& a, const EffectFrame& b, const std::vector<uint8_t>& pixels);

// Pixels of `surface` whose reference value moved between two frames by more than `threshold` (scalar effects, in
// the signal's units) or, for RGB, by more than `threshold` times the mean colour norm of `now` over the surface.
std::vector<uint8_t> changedPixels(const EffectFrame& before, const EffectFrame& now,
                                   const std::vector<uint8_t>& surface, float threshold);

// View distance of each pixel from the pre-pass depth (standard or reversed Z, the engine's near and far planes).
std::vector<float> viewDepth(const std::vector<float>& depth, float zNear, float zFar, bool reversedZ);
// Surface pixels of this frame that were not visible last frame: where the motion vector (pixels, this frame - last)
// leads out of the image, or to a last-frame pixel whose view depth differs by more than 5% (another surface). With
// no motion vectors (empty) the pixel is compared in place.
std::vector<uint8_t> disoccludedPixels(const std::vector<float>& depthNow, const std::vector<float>& depthBefore,
                                       const std::vector<glm::vec2>& motion, const std::vector<uint8_t>& surfaceNow,
                                       uint32_t width, uint32_t height);

std::vector<uint8_t> both(const std::vector<uint8_t>& a, const std::vector<uint8_t>& b);
uint64_t count(const std::vector<uint8_t>& pixels);

}  // namespace rbEffects
