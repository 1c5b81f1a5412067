// The ray budget of an adaptive pass with a time target (AdaptiveRaySettings::timeBudgetMs): from the pass's own
// measurement of a finished frame (GPU ms), the budget that would have taken the target time (that frame's budget
// scaled by target / ms: the budget, not the rays counted, because not every planned ray is traced: at half
// resolution a quarter of the plan is, and shadow pixels facing away from the light trace none),
// approached geometrically (half the log-distance per new measurement) so that one noisy timestamp or the frames
// in flight between planning and measuring do not make it oscillate, and by at most kMaxBudgetStep per measurement,
// so that one wild timestamp cannot plan a frame many times over its target. A fixed cost per frame (the planning
// dispatches, the launch) is no obstacle: at the fixed point rays * target / ms = rays, i.e. ms = target.
// Pure host logic, tested on a simulated cost model (tests/adaptive_rays_test.cpp).
//
// Thread safety: plain data, externally synchronised.
#pragma once

#include <raybridge/effects.h>

#include <array>
#include <cstdint>

namespace rb {

// The most one measurement may multiply or divide the budget by.
inline constexpr double kMaxBudgetStep = 2.0;

struct RayBudgetController {
  double budget = 0.0;     // rays of the frame being planned; 0 = not started
  uint64_t lastFrame = 0;  // PassStats::frame of the last measurement taken in
  // The budgets of the latest frames planned, by frame index, to scale the one a measurement names. A frame not
  // found (older than these) scales the rays it counted instead.
  struct Planned {
    uint64_t frame = 0;
    double budget = 0.0;
  };
  std::array<Planned, 16> planned{};
  // The rays to plan for frame `frame` (Context::frameIndex()). `latest`: the pass's latest finished measurement
  // (taken in once per frame it names); `initial`: where to start; the result stays within [minRays, maxRays].
  uint64_t next(uint64_t frame, const PassStats& latest, double targetMs, double initial, double minRays,
                double maxRays);
  void reset() { *this = {}; }
};

}  // namespace rb
