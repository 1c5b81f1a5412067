#include "adaptive_budget.h"

#include <algorithm>
#include <cmath>

namespace rb {

uint64_t RayBudgetController::next(uint64_t frame, const PassStats& latest, double targetMs, double initial,
                                   double minRays, double maxRays) {
  if (budget <= 0.0) budget = initial;
  if (latest.frame != 0 && latest.frame != lastFrame && latest.gpuMs > 0.0 && targetMs > 0.0) {
    double measured = double(latest.rays);  // the rays counted, when the frame's budget is no longer known
    for (const Planned& p : planned) {
      if (p.frame == latest.frame && p.budget > 0.0) measured = p.budget;
    }
    if (measured > 0.0) {
      lastFrame = latest.frame;
      // One measurement moves the budget by at most kMaxBudgetStep (after the half log-step): a single bad
      // timestamp (a hitch, a wrapped tick count, a near-zero reading) must not plan a frame a hundred times too
      // dear or too cheap, and the budget walks back from it in a few frames.
      const double current = std::max(budget, 1.0);
      const double ideal = std::clamp(measured * targetMs / latest.gpuMs, current / (kMaxBudgetStep * kMaxBudgetStep),
                                      current * kMaxBudgetStep * kMaxBudgetStep);
      budget = std::sqrt(current * std::max(ideal, 1.0));
    }
  }
  budget = std::clamp(budget, minRays, std::max(minRays, maxRays));
  const uint64_t rays = uint64_t(std::llround(budget));
  planned[frame % planned.size()] = {frame, double(rays)};
  return rays;
}

}  // namespace rb
