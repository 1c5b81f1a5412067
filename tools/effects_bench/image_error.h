// Error of an image against a reference over the surface pixels, the running sums a reference is accumulated
// in, and the PNGs the plotting script feeds to FLIP.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "sample_engine/result.h"

namespace rbEffects {

// 1 where the pre-pass saw a surface (depth < 1), 0 on the background.
std::vector<uint8_t> surfaceMask(const std::vector<float>& depth);
uint64_t countSet(const std::vector<uint8_t>& mask);

struct ErrorStats {
  double rmse = 0.0;  // sqrt(mean over surface pixels and channels of (test - reference)^2)
  double bias = 0.0;  // mean of (test - reference): < 0 = darker / more occluded than the reference
};
// `channels` values per pixel in `test`, `reference` uses the same layout.
ErrorStats compare(const std::vector<float>& test, const std::vector<float>& reference,
                   const std::vector<uint8_t>& mask, uint32_t channels);

// Running sums of frames with independent noise, split into two halves (even and odd frames) so that the
// reference's own noise can be estimated from the halves' disagreement.
class Accumulator {
 public:
  void add(const std::vector<float>& frame);
  uint32_t frames() const { return frames_[0] + frames_[1]; }
  std::vector<float> mean() const;              // over every frame
  std::vector<float> halfMean(int half) const;  // over the even (0) or odd (1) frames

 private:
  std::vector<double> sum_[2];
  uint32_t frames_[2] = {0, 0};
};

// RGBA (4 floats per pixel) -> RGB (3 floats per pixel).
std::vector<float> rgbOf(const std::vector<float>& rgba);

// A single-channel effect buffer in [0, 1] as an 8-bit grey PNG, sRGB-encoded so that a viewer (and FLIP, which
// decodes sRGB) sees the buffer's linear value: what a white surface lit by that visibility would look like.
sample_engine::Status writeGreyPng(const std::string& path, const std::vector<float>& values, uint32_t width,
                                   uint32_t height);
// Linear HDR RGB through the engine's tonemap (exposure, ACES fit, sRGB) as an 8-bit PNG.
sample_engine::Status writeTonemappedPng(const std::string& path, const std::vector<float>& rgb, uint32_t width,
                                         uint32_t height, float exposure);
// The surface mask as a black/white PNG (FLIP means are taken over its white pixels).
sample_engine::Status writeMaskPng(const std::string& path, const std::vector<uint8_t>& mask, uint32_t width,
                                   uint32_t height);

}  // namespace rbEffects
