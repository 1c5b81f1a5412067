// The frame budget (HybridEffectsDesc::budgetMs): one GPU time for the whole HybridEffects::record(), divided between
// the enabled effects frame after frame from the front end's own measurements of finished frames.
//
// What it moves, per effect (BudgetKnob):
//  - a time target, for an effect whose pass plans adaptive rays (denoised soft shadows and AO:
//    AdaptiveRaySettings::timeBudgetMs, which the pass's own RayBudgetController follows);
//  - a level on a short ladder, for the others (reflections: as described, then half resolution; stochastic local
//    lights: their rays halved down to one), level 0 as described, the last the cheapest.
// What it counts as fixed: the rest of what record() measures (the TLAS, the change masks, the denoisers, hard
// shadows).
//
// Each measurement (a finished frame): fixed = hook - the adjustable passes, and each levelled pass's cost at the level
// that frame ran, are smoothed (kBudgetSmoothing; a sample is clipped to 0.5x-1.5x the estimate, so one spike moves
// the estimate by at most 15%, and a lasting step is followed by up to 15% a frame). Each plan:
//  1. left = budget * (1 - headroom) - fixed - the levelled passes at their levels (headroom: kBudgetMinHeadroom);
//  2. levels, at most one step per kBudgetSettleFrames and only after two measurements at the current levels: a step
//     down (the one that saves most) while `left` is under what the adaptive effects need at least
//     (kBudgetAdaptiveShare of the budget); a step up (the cheapest, by its measured or predicted cost) only when
//     `left` after it still holds twice that. A step up that had to be undone within kBudgetRetryWindow frames waits
//     twice as long before it is tried again (up to kBudgetMaxBackoffFrames): the gap between the two thresholds and
//     the backoff keep the levels from oscillating;
//  3. adaptive targets: `left` in proportion to each effect's error weight (BudgetKnob::errorWeight: with a Monte
//     Carlo error a / sqrt(ms), the split that minimises the summed squared error gives each effect ms in proportion
//     to a). An effect that used under kBudgetUnderUse of its target for kBudgetSaturationFrames measurements in a
//     row without climbing (its rays at their maximum) is given what it uses plus a tenth (never more than its
//     share), and the rest goes to the others, until it uses 97% of that again.
// Before the first measurement every levelled effect is at its cheapest level and the adaptive targets at their least:
// a frame budget must hold from the first frames, and the levels climb as the measurements show room.
// A budget under the floor (fixed + the cheapest levels + the adaptive passes' least measured time) runs everything
// at its cheapest and reports belowFloor with the floor. Pure host logic, tested with injected timings
// (tests/frame_budget_test.cpp).
//
// Thread safety: plain data, externally synchronised.
#pragma once

#include <array>
#include <cstdint>

namespace rb {

// The effects a frame budget divides between (BudgetKnob, BudgetMeasurement and BudgetPlan index their arrays).
enum BudgetEffect : uint32_t { kBudgetShadows, kBudgetAo, kBudgetReflections, kBudgetLocalLights, kBudgetEffects };

// The longest level ladder.
inline constexpr uint32_t kBudgetMaxLevels = 8;
// The share of the budget kept free (p99 <= 1.1x budget): at least kBudgetMinHeadroom, and three times the mean
// frame-to-frame change of the hook (over the budget, smoothed; for a normal change about 2.4 standard deviations),
// which the plan, two frames late, cannot follow (a camera path's content changing, noise), up to kBudgetMaxHeadroom.
inline constexpr double kBudgetMinHeadroom = 0.05;
inline constexpr double kBudgetMaxHeadroom = 0.2;
// Weight of a new sample in the smoothed costs.
inline constexpr double kBudgetSmoothing = 0.3;
// What the adaptive effects together need at least, as a share of the budget, before a levelled effect keeps or
// gains a level: below it they would trace at their minimum, the noisiest image for the time.
inline constexpr double kBudgetAdaptiveShare = 0.15;
// The least time target of an adaptive effect (its pass then traces its minimum rays).
inline constexpr double kBudgetMinTargetMs = 0.02;
// The first measurements, over which the fixed cost is their least rather than smoothed: the first frames build the
// scene's BLASes (recordPendingWork inside record()), a load many times a frame's cost that smoothing would carry for
// twenty frames.
inline constexpr uint64_t kBudgetStartMeasurements = 4;
// Frames between two level steps: the frames in flight plus two measurements at the new level.
inline constexpr uint64_t kBudgetSettleFrames = 6;
// A step up undone within this many frames was a failed try: the next waits twice as long.
inline constexpr uint64_t kBudgetRetryWindow = 60;
inline constexpr uint64_t kBudgetMaxBackoffFrames = 960;
// Saturation of an adaptive effect (see the top).
inline constexpr double kBudgetUnderUse = 0.75;
inline constexpr uint32_t kBudgetSaturationFrames = 12;

// How the budget may adjust one effect.
struct BudgetKnob {
  bool enabled = false;   // the effect runs (its pass time is measured)
  bool adaptive = false;  // its pass takes a time target
  uint32_t levels = 1;    // its ladder (1 = fixed at its description; at most kBudgetMaxLevels)
  // Adaptive effects: the share of the time left goes in proportion to it (see the top).
  double errorWeight = 1.0;
  // Levelled effects: the predicted cost of a level over that of the next cheaper one, until both are measured.
  double stepCostRatio = 2.0;
};

// One finished frame, as record() measured it.
struct BudgetMeasurement {
  uint64_t frame = 0;                           // Context::frameIndex() of the frame measured
  double hookMs = 0.0;                          // the whole record()
  std::array<double, kBudgetEffects> passMs{};  // each effect's traced pass (its planning included, not its denoiser)
};

struct BudgetPlan {
  std::array<double, kBudgetEffects> targetMs{};  // adaptive effects' time targets; levelled ones' estimated cost
  std::array<uint32_t, kBudgetEffects> level{};   // levelled effects' level (0 = as described)
  double fixedMs = 0.0;                           // estimated fixed cost
  double floorMs = 0.0;                           // estimated least time of a frame
  bool belowFloor = false;                        // the budget is under floorMs: everything at its cheapest
  uint64_t measurements = 0;                      // measurements taken in
  uint64_t rejected = 0;                          // measurements refused (not finite, negative, unknown frame)
  uint64_t levelSteps = 0;                        // level steps so far
};

class FrameBudgetController {
 public:
  // Starts over with a budget (finite, > 0) and the effects' knobs: levelled effects at their cheapest.
  void configure(double budgetMs, const std::array<BudgetKnob, kBudgetEffects>& knobs);
  double budgetMs() const { return budget_; }
  // Takes in a finished frame's measurement, once per frame planned (a frame not planned, or planned too long ago to
  // be remembered, a value that is not finite or is negative: refused, counted in BudgetPlan::rejected).
  void measure(const BudgetMeasurement& m);
  // The plan of frame `frame` (remembered, so that its measurement is attributed to its levels).
  const BudgetPlan& plan(uint64_t frame);
  const BudgetPlan& latest() const { return plan_; }

 private:
  double levelCost(uint32_t e, uint32_t level) const;
  double headroom() const;
  double leftMs() const;
  double adaptiveNeedMs() const;
  void stepLevels(uint64_t frame);
  void splitAdaptive();

  double budget_ = 0.0;
  std::array<BudgetKnob, kBudgetEffects> knobs_{};
  BudgetPlan plan_;
  double fixed_ = -1.0;                                                      // < 0: not measured
  double lastHook_ = -1.0;                                                   // the latest measured hook (< 0: none)
  double change_ = 0.0;                                                      // smoothed |hook - previous hook| / budget
  std::array<std::array<double, kBudgetMaxLevels>, kBudgetEffects> cost_{};  // per level; 0 = not measured
  std::array<double, kBudgetEffects> use_{};                                 // adaptive passes' smoothed time
  std::array<double, kBudgetEffects> least_{};                               // adaptive passes' least time seen
  std::array<double, kBudgetEffects> previous_{};                            // adaptive passes' latest time
  std::array<uint32_t, kBudgetEffects> underUse_{};
  std::array<bool, kBudgetEffects> saturated_{};
  std::array<uint64_t, kBudgetEffects> upFrame_{}, backoff_{};
  uint64_t stepFrame_ = 0;         // the first frame planned at the current levels
  uint64_t measuredAtLevels_ = 0;  // measurements of frames planned at the current levels
  struct Planned {
    uint64_t frame = UINT64_MAX;
    std::array<uint32_t, kBudgetEffects> level{};
    std::array<double, kBudgetEffects> targetMs{};
  };
  std::array<Planned, 16> planned_{};
  uint64_t lastMeasured_ = UINT64_MAX;
};

}  // namespace rb
