// The three sweeps of the speed-vs-error scenario. Each traces its converged reference, then times and captures
// every traced and raster setting of the plan, and returns one row per method and setting.
//
//   shadows      error on the sun-visibility buffer: ShadowPass raw / denoised vs the engine's shadow map + PCF
//                (readbackShadowVisibility); soft sun of plan.sunRadiusDegrees.
//   ao           error on the open-fraction buffer: AoPass (binary, range = plan.aoRange) raw / denoised vs SSAO
//                (radius = plan.aoRange, readbackSsao).
//   reflections  error on the final HDR image: ReflectionPass (glossy rays) vs the constant sky or the
//                reflection probe (their only output is the lit image).
// AO and reflections also run their traced settings at half resolution (AoEffectSettings / ReflectionEffectSettings
// ::halfResolution): rows "traced_half_raw" and "traced_half_denoised", against the same full-resolution reference.
#pragma once

#include "sweep_common.h"

namespace rbEffects {

sample_engine::Result<EffectResult> runShadowSweep(FrameDriver& driver, const SweepPlan& plan);
sample_engine::Result<EffectResult> runAoSweep(FrameDriver& driver, const SweepPlan& plan);
sample_engine::Result<EffectResult> runReflectionSweep(FrameDriver& driver, const SweepPlan& plan);
// --scenario adaptive (adaptive_sweep.cpp): uniform against adaptive rays for `effect` (kEffectShadows or kEffectAo).
sample_engine::Result<EffectResult> runAdaptiveSweep(FrameDriver& driver, const SweepPlan& plan, rb::EffectBits effect);

}  // namespace rbEffects
