// What adaptive rays (adaptive_rays.h) and converged tiles (converged_tiles.h) read of a Denoiser, through its public
// history(): the history its latest record() wrote, and the reprojection from that frame's camera to the G-buffer
// about to be traced (the temporal pass's own). Kept-history marks go the other way through the Context
// (Context::Impl::markKeptHistory), keyed by the signal's view.
#pragma once

#include <raybridge/denoiser.h>

#include "pass_constants.h"

namespace rb::internal {

// The denoiser's history (Denoiser::history()) if it was written at the G-buffer's size, else an empty one (mean
// VK_NULL_HANDLE). Readers that need a Scalar history check the denoiser's signal() themselves.
DenoiseHistory historyFor(const Denoiser& denoiser, const GBufferDesc& g);
// The temporal pass's constants for `g` (camera, layout, reprojection from `history`'s camera; RB_DN_HISTORY when
// the history is valid), computed as the denoiser computes them; the settings-dependent fields are left 0. `frame`
// is the context's frame index; `who` names the caller in G-buffer errors.
Status historyReprojection(const DenoiseHistory& history, const GBufferDesc& g, uint64_t frame, const char* who,
                           DenoiseConstants& pc);

}  // namespace rb::internal
