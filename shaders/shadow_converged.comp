#version 460
#extension GL_GOOGLE_include_directive : require
// Converged-tile skipping, step 1 (before the classifier): a tile whose surface pixels all have a history of at
// least tc.minFrames frames with measured noise under tc.maxNoise has converged. Unless it is held (a recent refresh
// found a change) or it is one of this frame's refreshes (one frame in tc.refreshPeriod, the phase hashed per
// tile), it is skipped: its surface pixels get kept-history marks, -1 - their reprojected mean, which the denoiser
// reads as "no new frame, keep the history" (RB_DN_KEPT_MARKS), and its sky pixels their untraced 1.
//
// Why marks and not the reprojected mean as a new sample: the mean fed back as a frame would raise the frame count
// and shrink the measured noise with no ray behind them, so a tile would keep itself converged. The mark is also
// exact under camera motion: the denoiser reprojects the history to the pixel's new position by the same test as
// here (rbDnFindHistory), and a disoccluded pixel has no history, so its tile is never skipped.
#include "shadow_converged.glsl"

layout(set = 0, binding = RB_CONVERGED_BINDING_NOISE) uniform sampler2D noiseIn;  // .g: variance of the mean
layout(set = 0, binding = RB_CONVERGED_BINDING_VISIBILITY, r16f) uniform writeonly image2D outVisibility;

shared uint unconverged;
shared uint surfacePixels;
shared uint decision;

void main() {
  uint lane = gl_LocalInvocationIndex;
  if (lane == 0u) {
    unconverged = 0u;
    surfacePixels = 0u;
  }
  barrier();
  uvec2 pixel = gl_GlobalInvocationID.xy;
  ConvergedPixel c = rbConvergedPixel(pixel);
  if (c.surface) {
    atomicAdd(surfacePixels, 1u);
    float variance = c.history ? texelFetch(noiseIn, c.texel, 0).g : 1e30;
    bool converged = c.history && c.frames >= float(tc.minFrames) && variance < tc.maxNoise * tc.maxNoise;
    if (!converged) atomicAdd(unconverged, 1u);
  }
  barrier();
  if (lane == 0u) {
    uint tile = rbConvergedTile();
    uint hold = tileState[tile] & RB_TILE_HOLD_MASK;
    uint next = hold > 0u ? hold - 1u : 0u;
    if (unconverged == 0u && surfacePixels > 0u && hold == 0u) {
      uint phase = ((tile * 2654435761u) >> 16) % tc.refreshPeriod;
      next |= (tc.frameIndex + phase) % tc.refreshPeriod == 0u ? RB_TILE_REFRESH : RB_TILE_SKIP_CONVERGED;
    }
    tileState[tile] = next;
    decision = next;
  }
  barrier();
  if ((decision & RB_TILE_SKIP_CONVERGED) != 0u && c.inside) {
    imageStore(outVisibility, ivec2(pixel), vec4(c.surface ? -1.0 - c.mean : 1.0));
  }
}
