// HybridEffects' frame budget (HybridEffectsDesc::budgetMs; hybrid_effects.h, "Frame budget"): times the whole
// record() (HybridStats::hook, kept with or without a budget), takes each finished frame into the
// FrameBudgetController, and turns its plan into the passes' settings. Used by hybrid_effects.cpp alone.
//
// Thread safety: externally synchronised, as HybridEffects is.
#pragma once

#include <raybridge/hybrid_effects.h>

#include "frame_budget.h"
#include "pass_metrics.h"

namespace rb {

class EffectBudget {
 public:
  // The description's budget over its effects: restarts the controller when either changed. Fails, changing nothing
  // and naming the problem, when a budget is asked for on a queue family without timestamps.
  Status configure(Context& ctx, const HybridEffectsDesc& desc);
  void retire(Context& ctx);

  // At the start of record(), outside a render pass: the hook's start timestamp (with or without a budget).
  Status begin(Context& ctx, VkCommandBuffer cmd);
  void end(Context& ctx, VkCommandBuffer cmd);  // the hook's end timestamp

  bool active() const { return active_; }
  // With a budget, once per record(): takes the latest finished frame in (`passes`: the passes' latest stats; used
  // when they and the hook measured the same frame) and plans this frame.
  void plan(Context& ctx, const HybridStats& passes);
  // The plan on each effect's settings (nothing without a budget).
  void applyShadows(RaySchedule& s) const { applyAdaptive(s, kBudgetShadows); }
  void applyAo(RaySchedule& s) const { applyAdaptive(s, kBudgetAo); }
  // Reflections' glossy rays (0 = the default) and schedule at the planned level.
  void applyReflections(RaySchedule& s, uint32_t& raysPerPixel) const;
  uint32_t localLightRays(uint32_t described) const;

  PassStats hook(Context& ctx) { return hookReady_ ? hook_.latest(ctx) : PassStats{}; }
  FrameBudgetStats stats() const;

 private:
  void applyAdaptive(RaySchedule& s, BudgetEffect e) const;
  const BudgetPlan& latest() const { return controller_.latest(); }  // meaningful while active_

  PassMetrics hook_;
  bool hookReady_ = false;
  bool active_ = false;
  float budgetMs_ = 0.0f;
  std::array<BudgetKnob, kBudgetEffects> knobs_{};
  FrameBudgetController controller_;
};

}  // namespace rb
