// Reset rays (RaySchedule::resetRays): a pixel whose history restarts this frame, where the G-buffer's reactive mask
// is set (HybridEffects: the effect's change mask), traces GBufferConstants::resetRays rays instead of the pass's
// own count, so that its first frame is not several times its neighbours' error; so does a follow-up pixel (the
// mask above RB_REACTIVE_FOLLOW_UP only: restarted in one of the last frames), whose few frames are still far from its
// neighbours'. The denoiser weighs those frames by their rays (DenoiseSettings::resetFrames; denoise_temporal.comp).
// Include after the pass's push constant block.
#ifndef RAYBRIDGE_RESET_RAYS_GLSL
#define RAYBRIDGE_RESET_RAYS_GLSL

#include "raybridge_shader_interface.glsl"

layout(set = 0, binding = RB_BINDING_REACTIVE) uniform sampler2D gResetMask;  // the depth image again without a mask

// The rays `pixel` traces this frame: `count`, or resetRays where its history restarts or follows up a restart (the
// mask tests of rbDnReactive and rbDnFollowUp, denoise_common.glsl, so the denoiser's weighting agrees with the rays
// traced).
uint rbResetRayCount(ivec2 pixel, uint count) {
  if ((pc.gbuffer.flags & RB_GB_REACTIVE) == 0u || pc.gbuffer.resetRays <= count) return count;
  return texelFetch(gResetMask, pixel, 0).r > RB_REACTIVE_FOLLOW_UP ? pc.gbuffer.resetRays : count;
}

#endif
