#include "frame_budget.h"

#include <algorithm>
#include <cmath>

namespace rb {

namespace {

// An estimate of 0 (or below) is "not measured": the first sample sets it.
void smooth(double& estimate, double sample) {
  sample = std::max(sample, 1e-6);  // 0 marks "not measured"
  if (estimate <= 0.0) {
    estimate = sample;
    return;
  }
  estimate += kBudgetSmoothing * (std::clamp(sample, estimate * 0.5, estimate * 1.5) - estimate);
}

bool validTime(double ms) { return std::isfinite(ms) && ms >= 0.0; }

// A levelled effect's step up keeps this share of the budget beyond the adaptive effects' need, so that a step down
// (taken when nothing is left) and the step up are apart by more than the measurements' noise.
constexpr double kLevelMargin = 0.1;

}  // namespace

void FrameBudgetController::configure(double budgetMs, const std::array<BudgetKnob, kBudgetEffects>& knobs) {
  *this = FrameBudgetController{};
  budget_ = budgetMs;
  knobs_ = knobs;
  for (uint32_t e = 0; e < kBudgetEffects; ++e) {
    BudgetKnob& k = knobs_[e];
    k.levels = std::clamp(k.levels, 1u, kBudgetMaxLevels);
    if (!k.enabled) continue;
    plan_.level[e] = k.levels - 1;  // the cheapest until the measurements show room
    plan_.targetMs[e] = k.adaptive ? kBudgetMinTargetMs : 0.0;
  }
}

double FrameBudgetController::levelCost(uint32_t e, uint32_t level) const {
  if (cost_[e][level] > 0.0) return cost_[e][level];
  // The nearest measured level, scaled by the ratio per step (dearer towards level 0).
  for (uint32_t d = 1; d < kBudgetMaxLevels; ++d) {
    if (level + d < knobs_[e].levels && cost_[e][level + d] > 0.0)
      return cost_[e][level + d] * std::pow(knobs_[e].stepCostRatio, double(d));
    if (level >= d && cost_[e][level - d] > 0.0)
      return cost_[e][level - d] / std::pow(knobs_[e].stepCostRatio, double(d));
  }
  return 0.0;
}

double FrameBudgetController::headroom() const {
  return std::clamp(3.0 * change_, kBudgetMinHeadroom, kBudgetMaxHeadroom);
}

double FrameBudgetController::leftMs() const {
  double left = budget_ * (1.0 - headroom()) - std::max(fixed_, 0.0);
  for (uint32_t e = 0; e < kBudgetEffects; ++e) {
    if (knobs_[e].enabled && !knobs_[e].adaptive) left -= levelCost(e, plan_.level[e]);
  }
  return left;
}

double FrameBudgetController::adaptiveNeedMs() const {
  for (const BudgetKnob& k : knobs_) {
    if (k.enabled && k.adaptive) return kBudgetAdaptiveShare * budget_;
  }
  return 0.0;
}

void FrameBudgetController::measure(const BudgetMeasurement& m) {
  if (m.frame == lastMeasured_) return;  // the same finished frame again: nothing new
  const Planned* p = nullptr;
  for (const Planned& q : planned_) {
    if (q.frame == m.frame) p = &q;
  }
  bool valid = p != nullptr && validTime(m.hookMs);
  for (double ms : m.passMs) valid = valid && validTime(ms);
  if (!valid) {
    ++plan_.rejected;
    return;
  }
  lastMeasured_ = m.frame;
  ++plan_.measurements;
  // The frame-to-frame change over the budget, smoothed over about 20 frames; one change counts as at most a quarter
  // of the budget, so that a single spike (or the load's first frames) does not widen the headroom for long.
  if (lastHook_ >= 0.0 && plan_.measurements > kBudgetStartMeasurements) {
    const double change = std::min(std::abs(m.hookMs - lastHook_) / budget_, 0.25);
    change_ += 0.05 * (change - change_);
  }
  lastHook_ = m.hookMs;
  double passes = 0.0;
  for (uint32_t e = 0; e < kBudgetEffects; ++e) passes += knobs_[e].enabled ? m.passMs[e] : 0.0;
  double fixed = std::max(fixed_, 0.0);  // the first sample sets it (smooth() from "not measured")
  if (plan_.measurements <= kBudgetStartMeasurements && fixed > 0.0) {
    // The first frames also build the scene's BLASes (a load, not a frame's cost): their least is the estimate.
    fixed = std::min(fixed, std::max(m.hookMs - passes, 1e-6));
  } else {
    smooth(fixed, m.hookMs - passes);
  }
  fixed_ = fixed;
  for (uint32_t e = 0; e < kBudgetEffects; ++e) {
    const BudgetKnob& k = knobs_[e];
    if (!k.enabled) continue;
    if (!k.adaptive) {
      smooth(cost_[e][p->level[e]], m.passMs[e]);
      continue;
    }
    smooth(use_[e], m.passMs[e]);
    if (m.passMs[e] > 0.0) least_[e] = least_[e] > 0.0 ? std::min(least_[e], m.passMs[e]) : m.passMs[e];
    // Saturated: under kBudgetUnderUse of its target for kBudgetSaturationFrames measurements while its time did
    // not climb (a pass still climbing towards a new target is not saturated).
    const double target = p->targetMs[e];
    if (!saturated_[e]) {
      const bool under = m.passMs[e] < kBudgetUnderUse * target && m.passMs[e] <= 1.1 * previous_[e];
      underUse_[e] = under ? underUse_[e] + 1 : 0;
      saturated_[e] = underUse_[e] >= kBudgetSaturationFrames;
    } else if (m.passMs[e] >= 0.97 * target) {
      saturated_[e] = false;  // it uses what it is given again: back to its share
      underUse_[e] = 0;
    }
    previous_[e] = m.passMs[e];
  }
  if (p->level == plan_.level) ++measuredAtLevels_;
}

void FrameBudgetController::stepLevels(uint64_t frame) {
  if (frame < stepFrame_ + kBudgetSettleFrames || measuredAtLevels_ < 2) return;
  const double left = leftMs();
  const double need = adaptiveNeedMs();
  uint32_t best = kBudgetEffects;
  double bestValue = 0.0;
  if (left < need) {
    // Down: the step that saves most.
    for (uint32_t e = 0; e < kBudgetEffects; ++e) {
      const BudgetKnob& k = knobs_[e];
      const uint32_t l = plan_.level[e];
      if (!k.enabled || k.adaptive || l + 1 >= k.levels) continue;
      const double saving = levelCost(e, l) - levelCost(e, l + 1);
      if (best == kBudgetEffects || saving > bestValue) best = e, bestValue = saving;
    }
    if (best == kBudgetEffects) return;
    if (upFrame_[best] != 0 && frame - upFrame_[best] < kBudgetRetryWindow) {
      backoff_[best] = std::min(std::max(2 * backoff_[best], 4 * kBudgetSettleFrames), kBudgetMaxBackoffFrames);
    }
    ++plan_.level[best];
  } else {
    // Up: the cheapest step that leaves the adaptive effects twice their need, once its backoff has passed.
    for (uint32_t e = 0; e < kBudgetEffects; ++e) {
      const BudgetKnob& k = knobs_[e];
      const uint32_t l = plan_.level[e];
      if (!k.enabled || k.adaptive || l == 0 || frame < upFrame_[e] + backoff_[e]) continue;
      const double increase = levelCost(e, l - 1) - levelCost(e, l);
      if (left - increase < std::max(2.0 * need, kLevelMargin * budget_)) continue;
      if (best == kBudgetEffects || increase < bestValue) best = e, bestValue = increase;
    }
    if (best == kBudgetEffects) return;
    --plan_.level[best];
    upFrame_[best] = frame;
  }
  stepFrame_ = frame;
  measuredAtLevels_ = 0;
  ++plan_.levelSteps;
}

void FrameBudgetController::splitAdaptive() {
  // Water-filling by the error weights. A saturated effect takes what it uses plus a tenth, at most its share, and
  // leaves the rest to the others. An effect whose share is under the least it was measured at keeps its share as
  // its target (its pass goes to its minimum rays; a target at that least would hold it there) but counts that
  // least out of the others' split.
  std::array<bool, kBudgetEffects> out{};  // out of the split: its target is set
  double left = std::max(leftMs(), 0.0);
  for (uint32_t e = 0; e < kBudgetEffects; ++e) {
    if (knobs_[e].enabled && !knobs_[e].adaptive) plan_.targetMs[e] = levelCost(e, plan_.level[e]);
  }
  for (uint32_t round = 0; round <= kBudgetEffects; ++round) {
    double weights = 0.0;
    for (uint32_t e = 0; e < kBudgetEffects; ++e) {
      if (knobs_[e].enabled && knobs_[e].adaptive && !out[e]) weights += std::max(knobs_[e].errorWeight, 1e-6);
    }
    const double shared = std::max(left, 0.0);
    uint32_t settled = kBudgetEffects;  // the one effect taken out of the split this round
    double settledMs = 0.0;
    for (uint32_t e = 0; e < kBudgetEffects; ++e) {
      const BudgetKnob& k = knobs_[e];
      if (!k.enabled || !k.adaptive || out[e]) continue;
      const double share = shared * std::max(k.errorWeight, 1e-6) / weights;
      plan_.targetMs[e] = std::max(share, kBudgetMinTargetMs);
      if (settled != kBudgetEffects) continue;
      if (saturated_[e] && 1.1 * use_[e] < share) {
        settled = e, settledMs = plan_.targetMs[e] = std::max(1.1 * use_[e], kBudgetMinTargetMs);
      } else if (least_[e] > share) {
        settled = e, settledMs = least_[e];
      }
    }
    if (settled == kBudgetEffects) break;
    out[settled] = true;  // one at a time: the others' shares change as it leaves the split
    left -= settledMs;
  }
}

const BudgetPlan& FrameBudgetController::plan(uint64_t frame) {
  if (plan_.measurements > 0) {
    stepLevels(frame);
    splitAdaptive();
    plan_.fixedMs = fixed_;
    plan_.floorMs = fixed_;
    for (uint32_t e = 0; e < kBudgetEffects; ++e) {
      const BudgetKnob& k = knobs_[e];
      if (!k.enabled) continue;
      plan_.floorMs += k.adaptive ? std::max(least_[e], kBudgetMinTargetMs) : levelCost(e, k.levels - 1);
    }
    plan_.belowFloor = budget_ < plan_.floorMs;
  }
  Planned& p = planned_[frame % planned_.size()];
  p.frame = frame;
  p.level = plan_.level;
  p.targetMs = plan_.targetMs;
  return plan_;
}

}  // namespace rb
