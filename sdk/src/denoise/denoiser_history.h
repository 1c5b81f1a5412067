// What adaptive rays (adaptive_rays.h) and converged tiles (converged_tiles.h) read of a Denoiser, through its public
// history(): the history its latest record() wrote, and the reprojection from that frame's camera to the G-buffer
// about to be traced (the temporal pass's own). Kept-history marks go the other way through the Context
// (Context::Impl::markKeptHistory), keyed by the signal's view.
#pragma once

#include <raybridge/denoiser.h>

#include "pass_constants.h"
#include "ray_tracing_pipeline.h"

namespace rb::internal {

// The denoiser's history (Denoiser::history()) if it was written at the G-buffer's size, else an empty one (mean
// VK_NULL_HANDLE). Readers that need a Scalar history check the denoiser's signal() themselves.
DenoiseHistory historyFor(const Denoiser& denoiser, const GBufferDesc& g);
// The temporal pass's constants for `g` (camera, layout, reprojection from `history`'s camera; RB_DN_HISTORY when
// the history is valid), computed as the denoiser computes them; the settings-dependent fields are left 0. `frame`
// is the context's frame index; `who` names the caller in G-buffer errors.
Status historyReprojection(const DenoiseHistory& history, const GBufferDesc& g, uint64_t frame, const char* who,
                           DenoiseConstants& pc);

// Binds the G-buffer's motion vectors and reactive mask as every reader of a history binds them (the temporal passes,
// adaptive rays, converged tiles): an image the G-buffer does not have is the depth image again, never read (its
// RB_DN_MOTION / RB_DN_REACTIVE flag is off).
inline void writeReprojectionInputs(DescriptorWrites& w, const GBufferDesc& g, VkSampler sampler,
                                    uint32_t motionBinding, uint32_t reactiveBinding) {
  const GBufferImage& motion = g.motionVectors.view ? g.motionVectors : g.depth;
  const GBufferImage& reactive = g.reactiveMask.view ? g.reactiveMask : g.depth;
  w.sampledImage(motionBinding, motion.view, sampler, readLayout(motion));
  w.sampledImage(reactiveBinding, reactive.view, sampler, readLayout(reactive));
}

}  // namespace rb::internal
