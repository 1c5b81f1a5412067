#version 460
#extension GL_GOOGLE_include_directive : require
// Converged-tile skipping for RGB signals (reflections, local lights), step 1 (before the trace): a tile whose
// covered pixels (surfaces; reflections: under the roughness threshold) all have a history of at least tc.minFrames
// frames, whose mean's measured noise is under tc.maxNoise relative to its colour, and (reflections) whose view has
// turned by less than kMaxDrift lobe widths from the views its history holds, has converged. Unless it is held (a
// recent refresh found a change) or it is one of this frame's refreshes (one frame in tc.refreshPeriod, the phase hashed per tile), it is skipped: its covered pixels
// get kept-history marks, (their reprojected mean, a = -1), which the RGB denoiser reads as "no new frame, keep the
// history" (RB_DN_KEPT_MARKS), and the others what the pass writes there (reflections: (0, 0, 0, 0), no
// reflection; local lights: (0, 0, 0, 1) on the sky); the ray generation shader then skips its pixels. Counts the
// tiles traced and skipped (converged, or without a covered pixel: the ray generation shader writes those), the
// converged ones and the rays they saved (tc.denoise.signalRaysPerPixel per covered pixel, a mirror's 1), for
// PassStats.
//
// The view's turn is what the history cannot see: a glossy reflection seen from elsewhere is another reflection.
// It is summed over the frames (the state's drift bits), so a slow orbit is traced again once it has turned a
// quarter of a lobe, however slowly; a rotation of the camera alone turns nothing. A traced frame does not clear the
// sum: its rays replace only 1/frames of the running mean (the tile's longest history), so the sum shrinks by that
// much and the history's older views still count.
#include "rgb_converged.glsl"
#define RB_RAY_COUNTERS_BINDING RB_CONVERGED_BINDING_COUNTERS
#include "ray_counters.glsl"

layout(set = 0, binding = RB_CONVERGED_BINDING_VISIBILITY, rgba16f) uniform writeonly image2D outRadiance;

// The most a skipped tile's view may turn since its last trace, in widths of its glossiest pixel's lobe.
const float kMaxDrift = 0.25;
// Noise is relative to the colour's magnitude, down to this floor (an almost black reflection is not noise-free
// by dividing by nothing).
const float kNoiseFloorRadiance = 0.05;

shared uint unconverged;
shared uint coveredPixels;
shared uint driftUnits;  // this frame's largest drift in the tile, in RB_TILE_DRIFT_UNIT
shared uint rays;        // the rays of its covered pixels
shared uint maxFrames;   // the longest history among them
shared uint decision;

void main() {
  uint lane = gl_LocalInvocationIndex;
  if (lane == 0u) {
    unconverged = 0u;
    coveredPixels = 0u;
    driftUnits = 0u;
    rays = 0u;
    maxFrames = 0u;
  }
  barrier();
  uvec2 pixel = gl_GlobalInvocationID.xy;
  ConvergedRgb c = rbConvergedRgb(pixel);
  if (c.covered) {
    atomicAdd(coveredPixels, 1u);
    // The ray generation shader's count: every mirror ray would go the same way.
    atomicAdd(rays, c.mirror ? 1u : max(uint(pc.signalRaysPerPixel), 1u));
    float deviation = c.history ? sqrt(c.variance / max(c.frames, 1.0)) : 1e30;
    float scale = max(length(c.mean), kNoiseFloorRadiance);
    bool converged = c.history && c.frames >= float(tc.minFrames) && deviation < tc.maxNoise * scale;
    if (!converged) atomicAdd(unconverged, 1u);
    atomicMax(driftUnits, uint(min(c.drift / RB_TILE_DRIFT_UNIT, float(RB_TILE_DRIFT_MAX))));
    atomicMax(maxFrames, uint(c.frames));
  }
  barrier();
  if (lane == 0u) {
    uint tile = rbConvergedTile();
    uint state = tileState[tile];
    uint hold = state & RB_TILE_HOLD_MASK;
    uint drift = min((state >> RB_TILE_DRIFT_SHIFT) + driftUnits, RB_TILE_DRIFT_MAX);
    uint next = hold > 0u ? hold - 1u : 0u;
    bool still = float(drift) * RB_TILE_DRIFT_UNIT < kMaxDrift;
    if (unconverged == 0u && coveredPixels > 0u && hold == 0u && still) {
      uint phase = ((tile * 2654435761u) >> 16) % tc.refreshPeriod;
      next |= (tc.frameIndex + phase) % tc.refreshPeriod == 0u ? RB_TILE_REFRESH : RB_TILE_SKIP_CONVERGED;
    }
    // A skipped tile carries its drift on; a traced one forgets the share of its history that its rays replace.
    if ((next & RB_TILE_SKIP_CONVERGED) == 0u) drift = uint(float(drift) * (1.0 - 1.0 / max(float(maxFrames), 1.0)));
    next |= drift << RB_TILE_DRIFT_SHIFT;
    tileState[tile] = next;
    decision = next;
    if (coveredPixels == 0u) {
      atomicAdd(tilesSkipped, 1u);
    } else if ((next & RB_TILE_SKIP_CONVERGED) != 0u) {
      atomicAdd(tilesSkipped, 1u);
      atomicAdd(tilesConverged, 1u);
      atomicAdd(raysSaved, rays);
    } else {
      atomicAdd(tilesTraced, 1u);
    }
  }
  barrier();
  if ((decision & RB_TILE_SKIP_CONVERGED) != 0u && c.inside) {
    const vec4 uncovered = rbConvergedReflection() ? vec4(0.0) : vec4(0.0, 0.0, 0.0, 1.0);
    imageStore(outRadiance, ivec2(pixel), c.covered ? vec4(c.mean, -1.0) : uncovered);
  }
}
