// Shadows and AO: single-channel effects whose buffers are compared directly (traced raw, traced denoised,
// and the engine's raster counterpart read back from its own pass).
#include <algorithm>
#include <chrono>
#include <cstdio>

#include "effect_sweeps.h"

namespace rbEffects {

namespace se = sample_engine;
using Stats = rb::HybridStats;

namespace {

struct RasterSetting {
  std::string setting, id;
  nlohmann::json params;
  std::function<void(se::FrameParams&)> apply;
};

// Everything that differs between the shadow and the AO sweep.
struct ScalarEffect {
  std::string name, compared, effectMsNote;
  rb::EffectBits flag{};
  const char* passName = "";
  const char* denoiseName = "";
  rb::PassStats Stats::*pass = nullptr;
  rb::PassStats Stats::*denoise = nullptr;
  const char* rawImage = "";  // capture names (FrameDriver::capture)
  const char* denoisedImage = "";
  std::function<void(rb::HybridEffectsDesc&, uint32_t)> setRays;
  // Sets the effect's half-resolution tracing; null = the effect has none (no half-resolution rows).
  std::function<void(rb::HybridEffectsDesc&, bool)> setHalfResolution;
  std::vector<uint32_t> rays;
  uint32_t referenceRays = 0;
  se::FrameParams tracedParams;  // engine parameters of traced rows and of the reference
  std::vector<RasterSetting> raster;
  std::string rasterMsOf;
  double se::PassTimings::*rasterMs = nullptr;
  std::function<se::FrameParams(se::FrameParams)> forReadback;  // the raster capture frame's extra outputs
  std::function<se::Result<std::vector<float>>(se::Engine&)> readback;
};

se::Result<std::vector<float>> named(const rbRender::CapturedFrame& f, const char* name) {
  auto it = f.images.find(name);
  if (it == f.images.end())
    return se::Result<std::vector<float>>::failure(std::string("no captured '") + name + "' image");
  return se::Result<std::vector<float>>::success(it->second);
}

se::Result<EffectResult> runScalarSweep(FrameDriver& driver, const SweepPlan& plan, const ScalarEffect& fx) {
  using R = se::Result<EffectResult>;
  const auto start = std::chrono::steady_clock::now();
  EffectResult result;
  result.effect = fx.name;
  result.compared = fx.compared;
  result.effectMsNote = fx.effectMsNote;
  rbAdapter::Adapter& adapter = driver.adapter();
  rbAdapter::FrameSettings& s = adapter.settings();
  rb::HybridEffectsDesc desc;  // what the traced rows run, applied before each run
  auto apply = [&](bool denoise, uint32_t rays, bool halfResolution = false) {
    desc.effects = fx.flag;
    desc.shadows.disableDenoiser = desc.ao.disableDenoiser = !denoise;
    fx.setRays(desc, rays);
    if (fx.setHalfResolution) fx.setHalfResolution(desc, halfResolution);
    rb::Status st = adapter.effects().setDesc(desc);
    return st ? se::Status::success() : se::Status::failure("HybridEffects::setDesc: " + st.error().message);
  };
  const uint32_t w = plan.width, h = plan.height;
  auto grey = [&](const std::vector<float>& v) {
    return [&v, w, h](const std::string& p) { return writeGreyPng(p, v, w, h); };
  };

  // Reference: the raw traced buffer, many rays per frame, no denoiser, averaged over frames.
  s.enabled = true;
  const uint32_t perFrame = std::min(fx.referenceRays, kReferenceRaysPerFrame);
  if (se::Status st = apply(false, perFrame); !st) return R::failure(st.error);
  result.reference.raysPerFrame = perFrame;
  progress("%s: reference, %u rays per pixel (%u frames of %u)", fx.name.c_str(), fx.referenceRays,
           (fx.referenceRays + perFrame - 1) / perFrame, perFrame);
  auto ref = traceReference(
      driver, fx.tracedParams, (fx.referenceRays + perFrame - 1) / perFrame, 1,
      [&](const rbRender::CapturedFrame& f) { return named(f, fx.rawImage); }, fx.pass, result.reference);
  if (!ref) return R::failure(fx.name + " reference: " + ref.error);
  const std::vector<uint8_t>& mask = ref.value.mask;
  result.surfacePixels = countSet(mask);
  auto refImage = writeImage(plan, fx.name, "reference", grey(ref.value.values));
  if (!refImage) return R::failure(refImage.error);
  result.reference.image = refImage.value;
  if (auto m = writeImage(plan, fx.name, "mask", [&](const std::string& p) { return writeMaskPng(p, mask, w, h); }); !m)
    return R::failure(m.error);
  progress("%s: reference done in %.1f s (halves RMSE %.5f)", fx.name.c_str(), result.reference.seconds,
           result.reference.halvesRmse);

  // Every row, traced or raster, ends the same way: frame times, error against the reference, its image, a
  // progress line. Returns an error message, empty on success.
  auto finishRow = [&](Row& row, const nlohmann::json& engineMs, const std::vector<float>& values) -> std::string {
    row.frameMs = engineMs["frame"];
    row.engineMs = engineMs;
    const ErrorStats e = compare(values, ref.value.values, mask, 1);
    row.rmse = e.rmse;
    row.bias = e.bias;
    auto img = writeImage(plan, fx.name, row.id, grey(values));
    if (!img) return img.error;
    row.image = img.value;
    progress("%s: %-16s %-22s effect %8.3f ms  frame %8.3f ms  RMSE %.5f", fx.name.c_str(), row.method.c_str(),
             row.setting.c_str(), row.effectMs, row.frameMs, row.rmse);
    result.rows.push_back(std::move(row));
    return {};
  };

  // Traced rows: one run per ray count gives both the raw and the denoised row (the raw image stays available);
  // where the effect has half-resolution tracing, a second run at the same ray count gives its two rows.
  std::vector<std::pair<uint32_t, bool>> runs;
  for (uint32_t n : fx.rays) runs.push_back({n, false});
  if (fx.setHalfResolution)
    for (uint32_t n : fx.rays) runs.push_back({n, true});
  for (auto [n, half] : runs) {
    if (se::Status st = apply(true, n, half); !st) return R::failure(st.error);
    auto samples = driver.run(fx.tracedParams, plan.warmupFrames, plan.timedFrames);
    if (!samples) return R::failure(samples.error);
    // Single-frame denoising: the history is reset so that the capture frame's output uses that frame's rays
    // only (a static camera would otherwise accumulate the timed frames, which a moving camera cannot).
    adapter.effects().resetHistory();
    auto cap = driver.capture(fx.tracedParams);
    if (!cap) return R::failure(cap.error);
    const PassResult pass = passMedian(samples.value, fx.passName, fx.pass);
    const PassResult denoise = passMedian(samples.value, fx.denoiseName, fx.denoise);
    const nlohmann::json engineMs = engineMedians(samples.value);
    for (bool denoised : {false, true}) {
      auto values = named(cap.value, denoised ? fx.denoisedImage : fx.rawImage);
      if (!values) return R::failure(values.error);
      Row row;
      row.method = half ? (denoised ? "traced_half_denoised" : "traced_half_raw")
                        : (denoised ? "traced_denoised" : "traced_raw");
      row.setting = std::to_string(n) + (n == 1 ? " ray" : " rays") + (half ? ", half res" : "");
      row.id = row.method + "_r" + std::to_string(n);
      row.params = {{"rays_per_pixel", n}, {"denoised", denoised}};
      if (half) row.params["half_resolution"] = true;
      row.passes = {pass};
      if (denoised) row.passes.push_back(denoise);
      row.effectMs = pass.gpuMs + (denoised ? denoise.gpuMs : 0.0);
      row.effectMsOf = denoised ? std::string(fx.passName) + " + " + fx.denoiseName : fx.passName;
      if (std::string err = finishRow(row, engineMs, values.value); !err.empty()) return R::failure(err);
    }
  }

  // Raster rows: the adapter records nothing, the engine uses its own term and reads it back.
  s.enabled = false;
  for (const RasterSetting& rs : fx.raster) {
    se::FrameParams p = driver.baseParams();
    rs.apply(p);
    auto samples = driver.run(p, plan.warmupFrames, plan.timedFrames);
    if (!samples) return R::failure(samples.error);
    if (auto cap = driver.capture(fx.forReadback(p)); !cap) return R::failure(cap.error);
    auto values = fx.readback(driver.engine());
    if (!values) return R::failure(values.error);
    Row row;
    row.method = "raster";
    row.setting = rs.setting;
    row.id = "raster_" + rs.id;
    row.params = rs.params;
    const nlohmann::json engineMs = engineMedians(samples.value);
    row.effectMs = medianOf(samples.value, [&](const FrameSample& f) { return f.engine.*fx.rasterMs; });
    row.effectMsOf = fx.rasterMsOf;
    if (std::string err = finishRow(row, engineMs, values.value); !err.empty()) return R::failure(err);
  }
  s.enabled = true;
  selfCheck(result);
  result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return R::success(std::move(result));
}

}  // namespace

se::Result<EffectResult> runShadowSweep(FrameDriver& driver, const SweepPlan& plan) {
  ScalarEffect fx;
  fx.name = "shadows";
  fx.compared = "sun visibility buffer (1 = lit), surface pixels";
  fx.effectMsNote =
      "traced: ShadowPass (+ Denoiser) GPU ms; raster: the shadow-map pass only (the PCF lookups run inside the "
      "lighting pass and cannot be timed apart: compare frame ms too)";
  fx.flag = rb::kEffectShadows;
  fx.passName = "shadow";
  fx.denoiseName = "shadow_denoise";
  fx.pass = &Stats::shadow;
  fx.denoise = &Stats::shadowDenoise;
  fx.rawImage = "shadow_raw";
  fx.denoisedImage = "shadow";
  const float radius = plan.sunRadiusDegrees;
  fx.setRays = [radius](rb::HybridEffectsDesc& d, uint32_t n) {
    d.shadows.softAngularRadiusDegrees = radius;  // one ray too samples the disk (a noisy soft shadow, not hard)
    d.shadows.raysPerPixel = n;
  };
  fx.rays = plan.shadowRays;
  fx.referenceRays = plan.referenceShadows;
  fx.tracedParams = driver.baseParams();
  // Traced rows do not read the engine's shadow map, so it draws none.
  fx.tracedParams.shadow.enabled = false;
  for (auto [size, pcf] : plan.shadowMaps) {
    RasterSetting rs;
    rs.setting = "map " + std::to_string(size) + ", PCF " + std::to_string(pcf);
    rs.id = "map" + std::to_string(size) + "_pcf" + std::to_string(pcf);
    rs.params = {{"map_size", size}, {"pcf_kernel", pcf}};
    // Init-captures: Clang before 16 cannot capture structured bindings by name.
    rs.apply = [mapSize = size, kernel = pcf](se::FrameParams& p) {
      p.shadow.mapSize = mapSize;
      p.shadow.pcfKernelSize = kernel;
    };
    fx.raster.push_back(std::move(rs));
  }
  fx.rasterMsOf = "shadow map";
  fx.rasterMs = &se::PassTimings::shadowMs;
  fx.forReadback = [](se::FrameParams p) {
    p.outputShadowVisibility = true;
    return p;
  };
  fx.readback = [](se::Engine& e) { return e.readbackShadowVisibility(); };
  return runScalarSweep(driver, plan, fx);
}

se::Result<EffectResult> runAoSweep(FrameDriver& driver, const SweepPlan& plan) {
  ScalarEffect fx;
  fx.name = "ao";
  fx.compared = "ambient-occlusion open fraction (1 = open), surface pixels";
  fx.effectMsNote = "traced: AoPass (+ Denoiser) GPU ms; raster: the SSAO pass with its blur";
  fx.flag = rb::kEffectAo;
  fx.passName = "ao";
  fx.denoiseName = "ao_denoise";
  fx.pass = &Stats::ao;
  fx.denoise = &Stats::aoDenoise;
  fx.rawImage = "ao_raw";
  fx.denoisedImage = "ao";
  const float range = plan.aoRange;
  fx.setRays = [range](rb::HybridEffectsDesc& d, uint32_t n) {
    d.ao.raysPerPixel = n;
    d.ao.range = range;
    d.ao.estimator = rb::AoEstimator::Binary;  // the SSAO counterpart is binary too (occluded or not)
  };
  fx.setHalfResolution = [](rb::HybridEffectsDesc& d, bool half) { d.ao.schedule.halfResolution = half; };
  fx.rays = plan.aoRays;
  fx.referenceRays = plan.referenceAo;
  fx.tracedParams = driver.baseParams();
  for (uint32_t k : plan.ssaoKernels) {
    RasterSetting rs;
    rs.setting = "SSAO " + std::to_string(k);
    rs.id = "ssao" + std::to_string(k);
    rs.params = {{"ssao_kernel", k}, {"radius", range}, {"blur", true}};
    rs.apply = [k, range](se::FrameParams& p) {
      p.ssao.enabled = true;
      p.ssao.kernelSize = k;
      p.ssao.radius = range;
    };
    fx.raster.push_back(std::move(rs));
  }
  fx.rasterMsOf = "ssao";
  fx.rasterMs = &se::PassTimings::ssaoMs;
  fx.forReadback = [](se::FrameParams p) { return p; };
  fx.readback = [](se::Engine& e) { return e.readbackSsao(); };
  return runScalarSweep(driver, plan, fx);
}

}  // namespace rbEffects
