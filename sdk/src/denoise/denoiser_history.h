// What adaptive rays (adaptive_rays.h) and converged tiles (converged_tiles.h) read of a Denoiser: the
// history its latest record() wrote, and the reprojection from that frame's camera to the G-buffer about to be traced
// (the temporal pass's own).
#pragma once

#include <raybridge/denoiser.h>

#include "pass_constants.h"

namespace rb::internal {

struct DenoiserAccess {
  static const Denoiser::Impl& impl(const Denoiser& d) { return *d.impl_; }
};

struct DenoiserHistory {
  // In SHADER_READ_ONLY_OPTIMAL. A Scalar denoiser's: RG16F (mean, frames accumulated), R32F (view distance of each
  // pixel's surface) and RG16F (the latest temporal result: value, variance of its noise). An RGB or Reflection
  // denoiser's: RGBA16F (mean colour, frames), RG32F (view distance, variance of one frame's colour), no noise image.
  // VK_NULL_HANDLE when the denoiser has no images of the G-buffer's size (before its first record(), after a
  // resize). Readers that need a Scalar history check the denoiser's signal() themselves.
  VkImageView mean = VK_NULL_HANDLE;
  VkImageView distance = VK_NULL_HANDLE;
  VkImageView noise = VK_NULL_HANDLE;
  VkSampler sampler = VK_NULL_HANDLE;  // nearest, clamped: the denoiser's own
  bool valid = false;                  // false = the images hold no usable history (reset, temporal off)
};

DenoiserHistory latestHistory(const Denoiser& denoiser, const GBufferDesc& g);
// The signal of `denoiser`'s record() in frame `frame` holds kept-history marks (RB_DN_KEPT_MARKS): the pass it
// filters skipped converged tiles for it.
void expectKeptMarks(const Denoiser& denoiser, uint64_t frame);
// The temporal pass's constants for `g` (camera, layout, reprojection; RB_DN_HISTORY when the history is valid);
// the settings-dependent fields are left 0. `who` names the caller in G-buffer errors.
Status historyReprojection(const Denoiser& denoiser, const GBufferDesc& g, const char* who, DenoiseConstants& pc);

}  // namespace rb::internal
