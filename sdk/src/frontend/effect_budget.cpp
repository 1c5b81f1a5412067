#include "effect_budget.h"

#include <raybridge/many_light_pass.h>
#include <raybridge/reflection_pass.h>

#include <algorithm>
#include <bit>
#include <string>

namespace rb {

namespace {

// Where an adaptive effect's rays start under a budget (AdaptiveRaySettings::initialRaysPerPixel): at the planner's
// least (one ray per 64 pixels, or one tile), so that the first frames stay under the budget; they climb at most
// 2x a measurement to the target.
constexpr float kBudgetStartRaysPerPixel = 1.0f / 64.0f;
// The predicted cost of a reflection level over the next cheaper one, until both are measured: twice the rays (and,
// for the last step, four times the pixels at one ray: 2.8x on the perf scene, docs/performance.md "Half
// resolution"), so three, on the safe side: a step up that is predicted too cheap overruns once, then waits.
constexpr double kReflectionStepCost = 3.0;

// Reflection levels: the described glossy rays halved down to one (log2 + 1 levels), then, unless the description
// traces at half resolution already, one ray at half resolution.
uint32_t reflectionRays(const HybridEffectsDesc& d) {
  return d.reflections.raysPerPixel ? d.reflections.raysPerPixel : kDefaultReflectionRays;
}
uint32_t reflectionRayLevels(const HybridEffectsDesc& d) { return uint32_t(std::bit_width(reflectionRays(d))); }

bool sameKnobs(const std::array<BudgetKnob, kBudgetEffects>& a, const std::array<BudgetKnob, kBudgetEffects>& b) {
  for (uint32_t e = 0; e < kBudgetEffects; ++e) {
    if (a[e].enabled != b[e].enabled || a[e].adaptive != b[e].adaptive || a[e].levels != b[e].levels) return false;
  }
  return true;
}

}  // namespace

Status EffectBudget::configure(Context& ctx, const HybridEffectsDesc& desc) {
  if (desc.budgetMs > 0.0f && !ctx.deviceInfo().timestampsSupported) {
    return Error{ErrorCode::InvalidArgument, VK_SUCCESS,
                 "HybridEffectsDesc::budgetMs " + std::to_string(desc.budgetMs) +
                     " needs GPU timestamps, which the Context's queue family does not have (timestampValidBits " +
                     std::to_string(ctx.deviceInfo().timestampValidBits) +
                     "): set budgetMs = 0 and choose each effect's rays (or a preset) instead"};
  }
  // Denoised shadows and AO take a time target (hard shadows ignore it: their one ray is exact, a fixed cost).
  const bool shadows = desc.effects & kEffectShadows, ao = desc.effects & kEffectAo;
  std::array<BudgetKnob, kBudgetEffects> k{};
  k[kBudgetShadows] = {shadows, shadows && !desc.shadows.disableDenoiser, 1, kBudgetShadowErrorWeight, 2.0};
  k[kBudgetAo] = {ao, ao && !desc.ao.disableDenoiser, 1, kBudgetAoErrorWeight, 2.0};
  const uint32_t reflectionLevels = reflectionRayLevels(desc) + (desc.reflections.schedule.halfResolution ? 0u : 1u);
  k[kBudgetReflections] = {(desc.effects & kEffectReflections) != 0, false,
                           std::min(reflectionLevels, kBudgetMaxLevels), 1.0, kReflectionStepCost};
  // Stochastic local lights: their rays halved down to one (1 + log2 levels); the exact mode has nothing to move.
  const uint32_t lightRays = desc.localLights.raysPerPixel ? desc.localLights.raysPerPixel : kDefaultLightRays;
  const uint32_t lightLevels = desc.localLights.mode == ManyLightMode::Stochastic ? uint32_t(std::bit_width(lightRays))
                                                                                  : 1u;
  k[kBudgetLocalLights] = {(desc.effects & kEffectLocalLights) != 0, false, std::min(lightLevels, kBudgetMaxLevels),
                           1.0, 2.0};
  const bool wanted = desc.budgetMs > 0.0f;
  const bool restart = wanted && (!active_ || budgetMs_ != desc.budgetMs || !sameKnobs(k, knobs_));
  active_ = wanted;
  budgetMs_ = wanted ? desc.budgetMs : 0.0f;
  knobs_ = k;
  if (restart) controller_.configure(budgetMs_, knobs_);
  return {};
}

void EffectBudget::retire(Context& ctx) {
  if (hookReady_) hook_.retire(ctx);
  hookReady_ = false;
}

Status EffectBudget::begin(Context& ctx, VkCommandBuffer cmd) {
  if (!hookReady_) {
    if (Status st = hook_.init(ctx, "HybridEffects::record", false); !st) return st;
    hookReady_ = true;
  }
  if (Status st = hook_.beginRecording(ctx, cmd); !st) return st;
  hook_.writeStart(ctx, cmd);
  return {};
}

void EffectBudget::plan(Context& ctx, const HybridStats& passes) {
  if (!active_) return;
  const PassStats h = hook(ctx);
  const PassStats* of[kBudgetEffects] = {&passes.shadow, &passes.ao, &passes.reflection, &passes.localLights};
  BudgetMeasurement m;
  m.frame = h.frame;
  m.hookMs = h.gpuMs;
  bool sameFrame = h.frame != 0;
  for (uint32_t e = 0; e < kBudgetEffects; ++e) {
    if (!knobs_[e].enabled) continue;
    sameFrame = sameFrame && of[e]->frame == h.frame;  // a pass created since has no measurement of that frame
    m.passMs[e] = of[e]->gpuMs;
  }
  if (sameFrame) controller_.measure(m);
  controller_.plan(ctx.frameIndex());
}

void EffectBudget::end(Context& ctx, VkCommandBuffer cmd) {
  if (hookReady_) hook_.writeEnd(ctx, cmd);
}

void EffectBudget::applyAdaptive(RaySchedule& s, BudgetEffect e) const {
  if (!active_ || !knobs_[e].adaptive) return;
  s.adaptive.enabled = true;
  s.adaptive.timeBudgetMs = float(latest().targetMs[e]);
  s.adaptive.initialRaysPerPixel = kBudgetStartRaysPerPixel;
}

void EffectBudget::applyReflections(RaySchedule& s, uint32_t& raysPerPixel) const {
  if (!active_ || latest().level[kBudgetReflections] == 0) return;
  const uint32_t level = latest().level[kBudgetReflections];
  const uint32_t rays = raysPerPixel ? raysPerPixel : kDefaultReflectionRays;
  if (level < uint32_t(std::bit_width(rays))) {
    raysPerPixel = rays >> level;
    return;
  }
  raysPerPixel = 1;
  s.halfResolution = true;
  s.convergedTiles.enabled = false;  // a full-resolution stage
}

uint32_t EffectBudget::localLightRays(uint32_t described) const {
  if (!active_) return described;
  return std::max(1u, described >> latest().level[kBudgetLocalLights]);
}

FrameBudgetStats EffectBudget::stats() const {
  FrameBudgetStats s;
  if (!active_) return s;
  const BudgetPlan& p = latest();
  s.budgetMs = budgetMs_;
  s.fixedMs = p.fixedMs;
  s.floorMs = p.floorMs;
  s.belowFloor = p.belowFloor;
  s.shadowsMs = p.targetMs[kBudgetShadows];
  s.aoMs = p.targetMs[kBudgetAo];
  s.reflectionsMs = p.targetMs[kBudgetReflections];
  s.localLightsMs = p.targetMs[kBudgetLocalLights];
  s.reflectionLevel = p.level[kBudgetReflections];
  s.localLightLevel = p.level[kBudgetLocalLights];
  s.measurements = p.measurements;
  s.levelSteps = p.levelSteps;
  return s;
}

}  // namespace rb
