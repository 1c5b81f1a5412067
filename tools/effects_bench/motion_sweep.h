// --scenario motion: every denoised effect scored while the world and the camera move, frame by frame, against a
// converged reference of that frame's exact pose and time (the same passes, many rays, no denoiser, accumulated over
// frames with the scene frozen at that instant). Cases (motion_sweep.cpp): still, pan, turn, walkers, teleport, lamp
// jump, door. Metrics per case, effect and ray count: RMSE over the surface, over the pixels whose reference changed
// since the previous frame and over the newly visible ones; lag (frames after an event until the changed pixels'
// error is within 1.5x of a still sequence's at the same frame); the steady-state ratio of a moving object's changed
// pixels; flicker (mean absolute frame-to-frame change of the output against the reference's). See docs/effects.md,
// "Motion".
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "frame_driver.h"
#include "motion_scene.h"

namespace rbEffects {

// The mechanisms a run turns off or on, to measure what each buys or costs.
struct MotionSwitches {
  bool disableAntiLag = false;       // --no-anti-lag: DenoiseSettings::disableAntiLag
  bool disableChangeResets = false;  // --no-change-resets: HybridEffectsDesc::disableChangeResets
  bool convergedTiles = false;       // --converged-tiles: every effect skips its converged tiles (not the reference)
  // --no-short-history-filter: AoEffectSettings::disableShortHistoryFilter
  bool disableShortHistoryFilter = false;
  bool disableResetRays = false;     // --no-reset-rays: Shadow/AoEffectSettings::disableResetRays
  uint32_t resetRaysFactor = 0;      // --reset-rays-factor F: RaySchedule::resetRays = F x the rays; 0 = the default
  bool noReflectionChanges = false;  // --no-reflection-changes: ReflectionEffectSettings::disableRelitResets
  // --reset-follow-up N: HybridEffectsDesc::resetFollowUpFrames (0 = disableResetFollowUp); not given = the default
  std::optional<uint32_t> resetFollowUp;
};

struct MotionPlan {
  uint32_t width = 0, height = 0;
  uint32_t warmupFrames = 16;    // frames before the measured ones: the histories fill
  uint32_t measuredFrames = 10;  // captured and scored
  uint32_t eventFrame = 3;       // measured frame at which the pillar teleports and the lamp jumps
  uint32_t referenceFrames = 4;  // per measured frame
  uint32_t referenceRaysPerFrame = 64;
  std::vector<uint32_t> rays = {1, 4, 16};
  uint32_t stripRays = 4;  // the ray count whose teleport frames are written as PNGs
  double fps = 30.0;
  MotionSwitches switches;
  rb::EffectSet effects = 0;
  std::string imagesDir;           // "" = no PNGs
  std::vector<std::string> cases;  // the cases to run (kMotionCases); empty = all
};

// The published plan (GPU: 16 warm-up and 10 measured frames, references of 4 x 64 rays, 1, 4 and 16 rays) or, with
// `quick`, the ctest smoke run's (every case at 4 rays, few frames); `rays` (when not empty) replaces the ray counts.
MotionPlan makeMotionPlan(bool quick, uint32_t width, uint32_t height, rb::EffectSet effects, const std::string& images,
                          const MotionSwitches& switches, const std::vector<uint32_t>& rays);
// The smoke run's self-checks on a report: the teleport changed the reference (the animation played) and the still
// case did not (references frozen per frame, scene at rest: at most 2% of `pixels`, the references' noise). Returns
// the failures.
std::vector<std::string> motionChecks(const nlohmann::json& motion, uint64_t pixels);

// Runs every case at every ray count; returns the "motion" part of the JSON report, and prints a summary table.
sample_engine::Result<nlohmann::json> runMotionScenario(FrameDriver& driver, const MotionScene& scene,
                                                        const MotionPlan& plan);

}  // namespace rbEffects
