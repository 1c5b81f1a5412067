// Reflections: compared on the final HDR image, because the raster counterparts (constant sky, reflection probe)
// only exist inside the lighting pass. Shadows come from the engine's shadow map in every row (the same map),
// AO is off, so the reflected term is the only difference between rows. Then converged tiles
// (ReflectionSettings::convergedTiles, default settings) against uniform rays, denoised, over kConvergedFrames
// frames of the still camera at the most rays of the plan:
//   uniform_long           n rays in every pixel;
//   converged_tiles        the same with converged tiles skipped: the rays saved, the time, and the error.
#include <algorithm>
#include <chrono>
#include <cstdio>

#include "effect_sweeps.h"

namespace rbEffects {

namespace se = sample_engine;

namespace {

// The converged-tile rows: 16 frames to converge, 16 more with tiles skipped (and refreshed once in 8 frames), as
// the shadow and AO rows of --scenario adaptive.
constexpr uint32_t kConvergedFrames = 2 * rb::kDefaultConvergedMinFrames;

se::Result<std::vector<float>> hdrRgb(se::Engine& engine) {
  auto hdr = engine.readbackHdr();
  if (!hdr) return se::Result<std::vector<float>>::failure(hdr.error);
  return se::Result<std::vector<float>>::success(rgbOf(hdr.value.pixels));
}

}  // namespace

se::Result<EffectResult> runReflectionSweep(FrameDriver& driver, const SweepPlan& plan) {
  using R = se::Result<EffectResult>;
  const auto start = std::chrono::steady_clock::now();
  EffectResult result;
  result.effect = "reflections";
  result.compared = "final HDR image (linear RGB), surface pixels";
  result.effectMsNote = "traced: ReflectionPass (+ Denoiser) GPU ms; raster: the probe capture (a one-time cost, "
                        "recaptured only when the scene, "
                        "sun or sky change; 0 per frame otherwise), constant sky: no pass (0 ms)";
  rbAdapter::Adapter& adapter = driver.adapter();
  rbAdapter::FrameSettings& s = adapter.settings();
  const se::FrameParams base = driver.baseParams();
  const uint32_t w = plan.width, h = plan.height;
  auto png = [&](const std::vector<float>& rgb) {
    return [&rgb, w, h, exposure = base.exposure](const std::string& p) {
      return writeTonemappedPng(p, rgb, w, h, exposure);
    };
  };

  rb::HybridEffectsDesc desc;
  desc.effects = rb::kEffectReflections;
  // Every surface traces (threshold 1 by default): the engine treats untraced pixels as reflecting nothing, so a
  // lower threshold would make the reference itself wrong on rough surfaces.
  desc.reflections.roughnessThreshold = plan.reflectionRoughness;
  auto apply = [&](uint32_t rays, bool denoise = false, bool halfResolution = false) {
    desc.reflections.raysPerPixel = rays;
    desc.reflections.disableDenoiser = !denoise;
    desc.reflections.halfResolution = halfResolution;
    rb::Status st = adapter.effects().setDesc(desc);
    return st ? se::Status::success() : se::Status::failure("HybridEffects::setDesc: " + st.error().message);
  };
  s.enabled = true;
  const uint32_t perFrame = std::min(plan.referenceReflections, kReferenceRaysPerFrame);
  if (se::Status st = apply(perFrame); !st) return R::failure(st.error);
  const uint32_t frames = (plan.referenceReflections + perFrame - 1) / perFrame;
  result.reference.raysPerFrame = perFrame;
  progress("reflections: reference, %u rays per pixel (%u frames of %u)", plan.referenceReflections, frames, perFrame);
  auto ref = traceReference(
      driver, base, frames, 3, [&](const rbRender::CapturedFrame&) { return hdrRgb(driver.engine()); },
      &rb::HybridStats::reflection, result.reference);
  if (!ref) return R::failure("reflections reference: " + ref.error);
  const std::vector<uint8_t>& mask = ref.value.mask;
  result.surfacePixels = countSet(mask);
  auto refImage = writeImage(plan, "reflections", "reference", png(ref.value.values));
  if (!refImage) return R::failure(refImage.error);
  result.reference.image = refImage.value;
  if (auto m = writeImage(plan, "reflections", "mask",
                          [&](const std::string& p) { return writeMaskPng(p, mask, w, h); });
      !m)
    return R::failure(m.error);
  progress("reflections: reference done in %.1f s (halves RMSE %.5f)", result.reference.seconds,
           result.reference.halvesRmse);

  auto finish = [&](Row row, const std::vector<FrameSample>& samples, const std::vector<float>& rgb) -> se::Status {
    row.engineMs = engineMedians(samples);
    row.frameMs = row.engineMs["frame"];
    const ErrorStats e = compare(rgb, ref.value.values, mask, 3);
    row.rmse = e.rmse;
    row.bias = e.bias;
    auto img = writeImage(plan, "reflections", row.id, png(rgb));
    if (!img) return se::Status::failure(img.error);
    row.image = img.value;
    progress("reflections: %-16s %-22s effect %8.3f ms  frame %8.3f ms  RMSE %.5f", row.method.c_str(),
             row.setting.c_str(), row.effectMs, row.frameMs, row.rmse);
    result.rows.push_back(std::move(row));
    return se::Status::success();
  };

  // Traced rows: raw and denoised, each its own run (the engine composites whichever image the adapter hands it),
  // at full then at half resolution.
  for (bool half : {false, true}) {
    for (uint32_t n : plan.reflectionRays) {
      for (bool denoised : {false, true}) {
        if (se::Status st = apply(n, denoised, half); !st) return R::failure(st.error);
        auto samples = driver.run(base, plan.warmupFrames, plan.timedFrames);
        if (!samples) return R::failure(samples.error);
        // Single-frame denoising, as the shadow and AO rows: the captured frame uses its own rays only.
        adapter.effects().resetHistory();
        if (auto cap = driver.capture(base); !cap) return R::failure(cap.error);
        auto rgb = hdrRgb(driver.engine());
        if (!rgb) return R::failure(rgb.error);
        Row row;
        row.method = half ? (denoised ? "traced_half_denoised" : "traced_half_raw")
                          : (denoised ? "traced_denoised" : "traced_raw");
        row.setting = std::to_string(n) + (n == 1 ? " ray" : " rays") + (half ? ", half res" : "");
        row.id = row.method + "_r" + std::to_string(n);
        row.params = {{"rays_per_pixel", n}, {"roughness_threshold", plan.reflectionRoughness}, {"denoised", denoised}};
        if (half) row.params["half_resolution"] = true;
        const PassResult pass = passMedian(samples.value, "reflection", &rb::HybridStats::reflection);
        row.passes = {pass};
        row.effectMs = pass.gpuMs;
        row.effectMsOf = "reflection";
        if (denoised) {
          const PassResult dn = passMedian(samples.value, "reflection_denoise", &rb::HybridStats::reflectionDenoise);
          row.passes.push_back(dn);
          row.effectMs += dn.gpuMs;
          row.effectMsOf = "reflection + reflection_denoise";
        }
        if (se::Status st = finish(std::move(row), samples.value, rgb.value); !st) return R::failure(st.error);
      }
    }
  }

  // Converged tiles against uniform rays: history reset, kConvergedFrames frames, then the capture frame (with its
  // history); times are the medians of the second half, where tiles have converged.
  const uint32_t n = plan.reflectionRays.back();
  for (bool converged : {false, true}) {
    desc.reflections.convergedTiles.enabled = converged;
    if (se::Status st = apply(n, true); !st) return R::failure(st.error);
    adapter.effects().resetHistory();
    auto samples = driver.run(base, 0, kConvergedFrames);
    if (!samples) return R::failure(samples.error);
    if (auto cap = driver.capture(base); !cap) return R::failure(cap.error);
    auto rgb = hdrRgb(driver.engine());
    if (!rgb) return R::failure(rgb.error);
    const std::vector<FrameSample> settled(samples.value.begin() + kConvergedFrames / 2, samples.value.end());
    Row row;
    row.method = converged ? "converged_tiles" : "uniform_long";
    row.setting = std::to_string(n) + " rays, " + std::to_string(kConvergedFrames) + " frames";
    row.id = row.method + "_r" + std::to_string(n);
    row.params = {{"rays_per_pixel", n},
                  {"roughness_threshold", plan.reflectionRoughness},
                  {"denoised", true},
                  {"frames", kConvergedFrames},
                  {"converged_tiles", converged}};
    const PassResult pass = passMedian(settled, "reflection", &rb::HybridStats::reflection);
    const PassResult dn = passMedian(settled, "reflection_denoise", &rb::HybridStats::reflectionDenoise);
    row.passes = {pass, dn};
    row.effectMs = pass.gpuMs + dn.gpuMs;
    row.effectMsOf = "reflection + reflection_denoise";
    if (se::Status st = finish(std::move(row), settled, rgb.value); !st) return R::failure(st.error);
  }
  desc.reflections.convergedTiles.enabled = false;

  // Raster rows: constant sky (probe off) and the probe at each resolution.
  s.enabled = false;
  for (uint32_t size : plan.probeSizes) {
    se::FrameParams p = base;
    p.reflectionProbe.enabled = size > 0;
    p.reflectionProbe.resolution = size ? size : 64;
    // Each timed frame moves the probe up by a hair so that every one of them recaptures it: its capture cost
    // is measured over several frames, and the steady-state frame (without it) separately.
    // (The engine's default position, the bounds centre raised to heightAboveGround, moved by 0.1 mm steps.)
    const se::Bounds bounds = driver.engine().sceneBounds();
    glm::vec3 position = bounds.center();
    position.y = std::max(position.y, bounds.min.y + p.reflectionProbe.heightAboveGround);
    auto samples = driver.run(p, plan.warmupFrames, plan.timedFrames, [position](uint32_t i, se::FrameParams& q) {
      q.reflectionProbe.position = position + glm::vec3(0.0f, 1e-4f * float(i + 1), 0.0f);
    });
    if (!samples) return R::failure(samples.error);
    if (auto cap = driver.capture(p); !cap) return R::failure(cap.error);
    auto rgb = hdrRgb(driver.engine());
    if (!rgb) return R::failure(rgb.error);
    Row row;
    row.method = "raster";
    row.setting = size ? "probe " + std::to_string(size) : "constant sky";
    row.id = size ? "raster_probe" + std::to_string(size) : "raster_sky";
    row.params = {{"probe_resolution", size}};
    if (size) {
      std::vector<double> capture;
      for (const FrameSample& f : samples.value)
        if (f.engine.probeCaptured) capture.push_back(f.engine.probeMs);
      if (capture.empty()) return R::failure("reflections: no timed frame captured the probe");
      row.effectMs = median(capture);
    }
    row.effectMsOf = size ? "probe capture (one-time)" : "none";
    if (se::Status st = finish(std::move(row), samples.value, rgb.value); !st) return R::failure(st.error);
  }
  s.enabled = true;
  selfCheck(result);
  result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return R::success(std::move(result));
}

}  // namespace rbEffects
