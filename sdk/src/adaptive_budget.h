// The ray budget of an adaptive pass with a time target (AdaptiveRaySettings::timeBudgetMs): from the pass's own
// measurement of a finished frame (GPU ms and rays counted), the rays that would have taken the target time,
// approached geometrically (half the log-distance per new measurement) so that one noisy timestamp or the frames
// in flight between planning and measuring do not make it oscillate. A fixed cost per frame (the planning
// dispatches, the launch) is no obstacle: at the fixed point rays * target / ms = rays, i.e. ms = target.
// Pure host logic, tested on a simulated cost model (tests/adaptive_rays_test.cpp).
//
// Thread safety: plain data, externally synchronised.
#pragma once

#include <raybridge/effects.h>

#include <cstdint>

namespace rb {

struct RayBudgetController {
  double budget = 0.0;     // rays of the frame being planned; 0 = not started
  uint64_t lastFrame = 0;  // PassStats::frame of the last measurement taken in
  // The rays to plan this frame. `latest`: the pass's latest finished measurement (taken in once per frame it
  // names); `initial`: where to start; the result stays within [minRays, maxRays].
  uint64_t next(const PassStats& latest, double targetMs, double initial, double minRays, double maxRays);
  void reset() { *this = {}; }
};

}  // namespace rb
