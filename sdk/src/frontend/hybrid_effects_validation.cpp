// HybridEffectsDesc's validation (hybrid_effects_validation.h).
#include "hybrid_effects_validation.h"

#include <cmath>
#include <string>

#include "changed_box.h"
#include "light_validation.h"
#include "pass_constants.h"
#include "ray_schedule_stage.h"

namespace rb {

namespace {

Error invalid(std::string message) {
  return {ErrorCode::InvalidArgument, VK_SUCCESS, "HybridEffects: " + std::move(message)};
}

Status validateSize(uint32_t width, uint32_t height, const char* what) {
  if ((width == 0) != (height == 0) || width > kMaxHybridOutputSize || height > kMaxHybridOutputSize) {
    return invalid(std::string(what) + " " + std::to_string(width) + "x" + std::to_string(height) +
                   " is not a size: give both (1.." + std::to_string(kMaxHybridOutputSize) +
                   ") or neither (0x0 = follow the G-buffer)");
  }
  return {};
}

}  // namespace

Status validateHybridEffectsDesc(const HybridEffectsDesc& d) {
  if (d.effects & ~kAllEffects) return invalid("effects has unknown bits " + std::to_string(d.effects & ~kAllEffects));
  if (Status st = validateSize(d.width, d.height, "width x height"); !st) return st;
  const std::string maxRays = std::to_string(kMaxRaysPerPixel);
  if (d.shadows.raysPerPixel > kMaxRaysPerPixel)
    return invalid("shadows.raysPerPixel " + std::to_string(d.shadows.raysPerPixel) + " exceeds " + maxRays);
  if (!(d.shadows.softAngularRadiusDegrees >= 0.0f &&
        d.shadows.softAngularRadiusDegrees < kMaxLightAngularRadiusDegrees))
    return invalid("shadows.softAngularRadiusDegrees " + std::to_string(d.shadows.softAngularRadiusDegrees) +
                   " is outside [0, " + std::to_string(int(kMaxLightAngularRadiusDegrees)) + ")");
  if (d.ao.raysPerPixel > kMaxRaysPerPixel)
    return invalid("ao.raysPerPixel " + std::to_string(d.ao.raysPerPixel) + " exceeds " + maxRays);
  if (!(d.ao.range >= 0.0f) || !std::isfinite(d.ao.range))
    return invalid("ao.range " + std::to_string(d.ao.range) + " must be >= 0 and finite");
  if (!(d.reflections.roughnessThreshold >= 0.0f && d.reflections.roughnessThreshold <= 1.0f))
    return invalid("reflections.roughnessThreshold " + std::to_string(d.reflections.roughnessThreshold) +
                   " is outside [0, 1]");
  if (d.localLights.mode != ManyLightMode::Stochastic && d.localLights.mode != ManyLightMode::Exact)
    return invalid("localLights.mode has an unknown value");
  if (d.tlasMode > TlasBuildMode::UpdateIfPossible)
    return invalid("tlasMode " + std::to_string(int(d.tlasMode)) +
                   " is not a TlasBuildMode (Adaptive, Rebuild or UpdateIfPossible)");
  if (d.localLights.raysPerPixel > 64 || d.localLights.candidates > 64)
    return invalid("localLights.raysPerPixel " + std::to_string(d.localLights.raysPerPixel) + " and candidates " +
                   std::to_string(d.localLights.candidates) + " must be at most 64");
  if (d.reflections.raysPerPixel > 64)
    return invalid("reflections.raysPerPixel " + std::to_string(d.reflections.raysPerPixel) + " exceeds 64");
  if (!(d.budgetMs >= 0.0f && d.budgetMs <= kMaxFrameBudgetMs))
    return invalid("budgetMs " + std::to_string(d.budgetMs) + " is not a frame budget: give GPU milliseconds in (0, " +
                   std::to_string(int(kMaxFrameBudgetMs)) + "], or 0 for none");
  if (d.resetFollowUpFrames > kMaxResetFollowUpFrames)
    return invalid("resetFollowUpFrames " + std::to_string(d.resetFollowUpFrames) +
                   " exceeds kMaxResetFollowUpFrames (" + std::to_string(kMaxResetFollowUpFrames) +
                   "); set disableResetFollowUp for none");
  // Each effect's schedule by the one validator, then against its denoiser (history is the effect's own).
  struct Scheduled {
    const RaySchedule& schedule;
    uint32_t capabilities;
    DenoiseSignal signal;
    const char* field;
    bool denoised;
    const char* denoiserFix;
  };
  const bool stochasticLights = d.localLights.mode == ManyLightMode::Stochastic;
  const Scheduled scheduled[] = {
      {d.shadows.schedule, kShadowScheduleCapabilities, DenoiseSignal::Scalar, "shadows", !d.shadows.disableDenoiser,
       "shadows.disableDenoiser = false"},
      {d.ao.schedule, kAoScheduleCapabilities, DenoiseSignal::Scalar, "ao", !d.ao.disableDenoiser,
       "ao.disableDenoiser = false"},
      {d.reflections.schedule, kReflectionScheduleCapabilities, DenoiseSignal::Reflection, "reflections",
       !d.reflections.disableDenoiser, "reflections.disableDenoiser = false"},
      {d.localLights.schedule, kLocalLightScheduleCapabilities, DenoiseSignal::Rgb, "localLights",
       !d.localLights.disableDenoiser && stochasticLights,
       "localLights.mode = Stochastic and localLights.disableDenoiser = false (only that mode is denoised)"},
  };
  for (const Scheduled& e : scheduled) {
    const std::string field = std::string("HybridEffects: HybridEffectsDesc::") + e.field + ".schedule";
    if (Status st = validateRaySchedule(e.schedule, e.capabilities, e.signal, field, true); !st) return st;
    const char* user = e.schedule.adaptive.enabled         ? "adaptive.enabled: adaptive rays plan from"
                       : e.schedule.convergedTiles.enabled ? "convergedTiles.enabled: converged tiles are read from"
                                                           : nullptr;
    if (user && !e.denoised) {
      return Error{ErrorCode::InvalidArgument, VK_SUCCESS,
                   field + "." + user + " the effect's denoiser's history: set " + e.denoiserFix + ", or disable it"};
    }
  }
  return {};
}

Status validateHybridFrame(const HybridEffectsDesc& d, const HybridFrame& frame, bool lit) {
  if (d.width && (frame.gbuffer.width != d.width || frame.gbuffer.height != d.height)) {
    return invalid("record: HybridFrame::gbuffer is " + std::to_string(frame.gbuffer.width) + "x" +
                   std::to_string(frame.gbuffer.height) + " but the outputs are " + std::to_string(d.width) + "x" +
                   std::to_string(d.height) + ": call resize(" + std::to_string(frame.gbuffer.width) + ", " +
                   std::to_string(frame.gbuffer.height) + ") when the G-buffer changes size");
  }
  // The hand-over (gbuffer.h) before anything is recorded: a bad layout, usage or aspect names its field.
  if (Status st = validateGBufferImages(frame.gbuffer, "HybridEffects: record: HybridFrame::gbuffer"); !st) return st;
  if (frame.reflectionGBuffer) {
    if (Status st = validateGBufferImages(*frame.reflectionGBuffer, "HybridEffects: record: reflectionGBuffer"); !st)
      return st;
  }
  // The light shadows and lights reflection hits: checked as every effect checks a light.
  if (lit) {
    if (Status st = validateLight(frame.light, "HybridEffects: record: HybridFrame::light: "); !st) return st;
  }
  if (frame.changedBoxes.size() > kMaxEngineChangedBoxes) {
    return invalid("record: HybridFrame::changedBoxes holds " + std::to_string(frame.changedBoxes.size()) +
                   " boxes, more than kMaxEngineChangedBoxes (" + std::to_string(kMaxEngineChangedBoxes) +
                   "); merge nearby ones, or reset the history (resetHistory) for a change that large");
  }
  for (size_t i = 0; i < frame.changedBoxes.size(); ++i) {
    const ChangedBox& b = frame.changedBoxes[i];
    if (const int k = invalidChangedBoxAxis(b); k >= 0) {
      return invalid("record: HybridFrame::changedBoxes[" + std::to_string(i) + "] has min " +
                     std::to_string(b.min[k]) + " and max " + std::to_string(b.max[k]) + " on axis " +
                     std::to_string(k) + "; give finite world-space corners with min <= max");
    }
  }
  return {};
}

}  // namespace rb
