#include "adaptive_budget.h"

#include <algorithm>
#include <cmath>

namespace rb {

uint64_t RayBudgetController::next(const PassStats& latest, double targetMs, double initial, double minRays,
                                   double maxRays) {
  if (budget <= 0.0) budget = initial;
  if (latest.frame != 0 && latest.frame != lastFrame && latest.gpuMs > 0.0 && latest.rays > 0 && targetMs > 0.0) {
    lastFrame = latest.frame;
    const double ideal = double(latest.rays) * targetMs / latest.gpuMs;
    budget = std::sqrt(std::max(budget, 1.0) * std::max(ideal, 1.0));
  }
  budget = std::clamp(budget, minRays, std::max(minRays, maxRays));
  return uint64_t(std::llround(budget));
}

}  // namespace rb
