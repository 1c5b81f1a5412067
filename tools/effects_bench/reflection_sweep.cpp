// Reflections: compared on the final HDR image, because the raster counterparts (constant sky, reflection probe)
// only exist inside the lighting pass. Shadows come from the engine's shadow map in every row (the same map),
// AO is off, so the reflected term is the only difference between rows. Then converged tiles
// (ReflectionSettings::schedule.convergedTiles, default settings) against uniform rays, denoised, over kConvergedFrames
// frames of the still camera at the most rays of the plan:
//   uniform_long           n rays in every pixel;
//   converged_tiles        the same with converged tiles skipped: the rays saved, the time, and the error.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <functional>
#include <string>
#include <vector>

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

// The sweep's state between its parts: the reflection settings the traced rows change, the converged reference,
// and the rows measured so far.
class ReflectionSweep {
 public:
  ReflectionSweep(FrameDriver& driver, const SweepPlan& plan)
      : driver_(driver), plan_(plan), adapter_(driver.adapter()), base_(driver.baseParams()) {
    result_.effect = "reflections";
    result_.compared = "final HDR image (linear RGB), surface pixels";
    result_.effectMsNote = "traced: ReflectionPass (+ Denoiser) GPU ms; raster: the probe capture (a one-time cost, "
                           "recaptured only when the scene, "
                           "sun or sky change; 0 per frame otherwise), constant sky: no pass (0 ms)";
    desc_.effects = rb::kEffectReflections;
    // Every surface traces (threshold 1 by default): the engine treats untraced pixels as reflecting nothing, so a
    // lower threshold would make the reference itself wrong on rough surfaces.
    desc_.reflections.roughnessThreshold = plan.reflectionRoughness;
  }

  // The reference in frames of at most kReferenceRaysPerFrame rays, and its picture and surface mask.
  std::string traceReference() {
    adapter_.settings().enabled = true;
    const uint32_t perFrame = std::min(plan_.referenceReflections, kReferenceRaysPerFrame);
    if (se::Status st = apply(perFrame); !st) return st.error;
    const uint32_t frames = (plan_.referenceReflections + perFrame - 1) / perFrame;
    result_.reference.raysPerFrame = perFrame;
    progress("reflections: reference, %u rays per pixel (%u frames of %u)", plan_.referenceReflections, frames,
             perFrame);
    FrameDriver& driver = driver_;
    auto ref = rbEffects::traceReference(
        driver_, base_, frames, 3, [&driver](const rbRender::CapturedFrame&) { return hdrRgb(driver.engine()); },
        &rb::HybridStats::reflection, result_.reference);
    if (!ref) return "reflections reference: " + ref.error;
    ref_ = std::move(ref.value);
    const std::vector<uint8_t>& mask = ref_.mask;
    result_.surfacePixels = countSet(mask);
    auto refImage = writeImage(plan_, "reflections", "reference", png(ref_.values));
    if (!refImage) return refImage.error;
    result_.reference.image = refImage.value;
    const uint32_t w = plan_.width, h = plan_.height;
    if (auto m = writeImage(plan_, "reflections", "mask",
                            [&](const std::string& p) { return writeMaskPng(p, mask, w, h); });
        !m)
      return m.error;
    progress("reflections: reference done in %.1f s (halves RMSE %.5f)", result_.reference.seconds,
             result_.reference.halvesRmse);
    return {};
  }

  // Traced rows: raw and denoised, each its own run (the engine composites whichever image the adapter hands it),
  // at full then at half resolution.
  std::string tracedRows() {
    for (bool half : {false, true}) {
      for (uint32_t n : plan_.reflectionRays) {
        for (bool denoised : {false, true})
          if (std::string err = tracedRow(n, denoised, half); !err.empty()) return err;
      }
    }
    return {};
  }

  // Converged tiles against uniform rays: history reset, kConvergedFrames frames, then the capture frame (with its
  // history); times are the medians of the second half, where tiles have converged.
  std::string convergedTileRows() {
    const uint32_t n = plan_.reflectionRays.back();
    for (bool converged : {false, true}) {
      desc_.reflections.schedule.convergedTiles.enabled = converged;
      if (se::Status st = apply(n, true); !st) return st.error;
      adapter_.effects().resetHistory();
      auto samples = driver_.run(base_, 0, kConvergedFrames);
      if (!samples) return samples.error;
      if (auto cap = driver_.capture(base_); !cap) return cap.error;
      auto rgb = hdrRgb(driver_.engine());
      if (!rgb) return rgb.error;
      const std::vector<FrameSample> settled(samples.value.begin() + kConvergedFrames / 2, samples.value.end());
      Row row;
      row.method = converged ? "converged_tiles" : "uniform_long";
      row.setting = std::to_string(n) + " rays, " + std::to_string(kConvergedFrames) + " frames";
      row.id = row.method + "_r" + std::to_string(n);
      row.params = {{"rays_per_pixel", n},
                    {"roughness_threshold", plan_.reflectionRoughness},
                    {"denoised", true},
                    {"frames", kConvergedFrames},
                    {"converged_tiles", converged}};
      const PassResult pass = passMedian(settled, "reflection", &rb::HybridStats::reflection);
      const PassResult dn = passMedian(settled, "reflection_denoise", &rb::HybridStats::reflectionDenoise);
      row.passes = {pass, dn};
      row.effectMs = pass.gpuMs + dn.gpuMs;
      row.effectMsOf = "reflection + reflection_denoise";
      if (se::Status st = finish(std::move(row), settled, rgb.value); !st) return st.error;
    }
    desc_.reflections.schedule.convergedTiles.enabled = false;
    return {};
  }

  // Raster rows: constant sky (probe off) and the probe at each resolution. The adapter is off for them.
  std::string rasterRows() {
    adapter_.settings().enabled = false;
    for (uint32_t size : plan_.probeSizes)
      if (std::string err = rasterRow(size); !err.empty()) return err;
    adapter_.settings().enabled = true;
    return {};
  }

  EffectResult& result() { return result_; }

 private:
  se::Status apply(uint32_t rays, bool denoise = false, bool halfResolution = false) {
    desc_.reflections.raysPerPixel = rays;
    desc_.reflections.disableDenoiser = !denoise;
    desc_.reflections.schedule.halfResolution = halfResolution;
    rb::Status st = adapter_.effects().setDesc(desc_);
    return st ? se::Status::success() : se::Status::failure("HybridEffects::setDesc: " + st.error().message);
  }

  // Writes `rgb` tonemapped as the reference is; `rgb` must outlive the writer.
  std::function<se::Status(const std::string&)> png(const std::vector<float>& rgb) const {
    return [&rgb, w = plan_.width, h = plan_.height, exposure = base_.exposure](const std::string& p) {
      return writeTonemappedPng(p, rgb, w, h, exposure);
    };
  }

  // The row's engine times, its error against the reference and its picture; then it joins the result.
  se::Status finish(Row row, const std::vector<FrameSample>& samples, const std::vector<float>& rgb) {
    row.engineMs = engineMedians(samples);
    row.frameMs = row.engineMs["frame"];
    const ErrorStats e = compare(rgb, ref_.values, ref_.mask, 3);
    row.rmse = e.rmse;
    row.bias = e.bias;
    auto img = writeImage(plan_, "reflections", row.id, png(rgb));
    if (!img) return se::Status::failure(img.error);
    row.image = img.value;
    progress("reflections: %-16s %-22s effect %8.3f ms  frame %8.3f ms  RMSE %.5f", row.method.c_str(),
             row.setting.c_str(), row.effectMs, row.frameMs, row.rmse);
    result_.rows.push_back(std::move(row));
    return se::Status::success();
  }

  std::string tracedRow(uint32_t n, bool denoised, bool half) {
    if (se::Status st = apply(n, denoised, half); !st) return st.error;
    auto samples = driver_.run(base_, plan_.warmupFrames, plan_.timedFrames);
    if (!samples) return samples.error;
    // Single-frame denoising, as the shadow and AO rows: the captured frame uses its own rays only.
    adapter_.effects().resetHistory();
    if (auto cap = driver_.capture(base_); !cap) return cap.error;
    auto rgb = hdrRgb(driver_.engine());
    if (!rgb) return rgb.error;
    Row row;
    row.method = half ? (denoised ? "traced_half_denoised" : "traced_half_raw")
                      : (denoised ? "traced_denoised" : "traced_raw");
    row.setting = std::to_string(n) + (n == 1 ? " ray" : " rays") + (half ? ", half res" : "");
    row.id = row.method + "_r" + std::to_string(n);
    row.params = {{"rays_per_pixel", n}, {"roughness_threshold", plan_.reflectionRoughness}, {"denoised", denoised}};
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
    se::Status st = finish(std::move(row), samples.value, rgb.value);
    return st ? std::string() : st.error;
  }

  std::string rasterRow(uint32_t size) {
    se::FrameParams p = base_;
    p.reflectionProbe.enabled = size > 0;
    p.reflectionProbe.resolution = size ? size : 64;
    // Each timed frame moves the probe up by a hair so that every one of them recaptures it: its capture cost
    // is measured over several frames, and the steady-state frame (without it) separately.
    // (The engine's default position, the bounds centre raised to heightAboveGround, moved by 0.1 mm steps.)
    const se::Bounds bounds = driver_.engine().sceneBounds();
    glm::vec3 position = bounds.center();
    position.y = std::max(position.y, bounds.min.y + p.reflectionProbe.heightAboveGround);
    auto samples = driver_.run(p, plan_.warmupFrames, plan_.timedFrames, [position](uint32_t i, se::FrameParams& q) {
      q.reflectionProbe.position = position + glm::vec3(0.0f, 1e-4f * float(i + 1), 0.0f);
    });
    if (!samples) return samples.error;
    if (auto cap = driver_.capture(p); !cap) return cap.error;
    auto rgb = hdrRgb(driver_.engine());
    if (!rgb) return rgb.error;
    Row row;
    row.method = "raster";
    row.setting = size ? "probe " + std::to_string(size) : "constant sky";
    row.id = size ? "raster_probe" + std::to_string(size) : "raster_sky";
    row.params = {{"probe_resolution", size}};
    if (size) {
      std::vector<double> capture;
      for (const FrameSample& f : samples.value)
        if (f.engine.probeCaptured) capture.push_back(f.engine.probeMs);
      if (capture.empty()) return "reflections: no timed frame captured the probe";
      row.effectMs = median(capture);
    }
    row.effectMsOf = size ? "probe capture (one-time)" : "none";
    se::Status st = finish(std::move(row), samples.value, rgb.value);
    return st ? std::string() : st.error;
  }

  FrameDriver& driver_;
  const SweepPlan& plan_;
  rbAdapter::Adapter& adapter_;
  const se::FrameParams base_;
  rb::HybridEffectsDesc desc_;
  EffectResult result_;
  ReferenceImage ref_;
};

}  // namespace

se::Result<EffectResult> runReflectionSweep(FrameDriver& driver, const SweepPlan& plan) {
  using R = se::Result<EffectResult>;
  const auto start = std::chrono::steady_clock::now();
  ReflectionSweep sweep(driver, plan);
  if (std::string err = sweep.traceReference(); !err.empty()) return R::failure(err);
  if (std::string err = sweep.tracedRows(); !err.empty()) return R::failure(err);
  if (std::string err = sweep.convergedTileRows(); !err.empty()) return R::failure(err);
  if (std::string err = sweep.rasterRows(); !err.empty()) return R::failure(err);
  EffectResult& result = sweep.result();
  selfCheck(result);
  result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return R::success(std::move(result));
}

}  // namespace rbEffects
