// The adaptive-rays scenario (--scenario adaptive): soft shadows and AO accumulated over frames with the denoiser
// on a still camera, uniform rays per pixel against adaptive rays (raybridge/adaptive_rays.h), each scored by the
// RMSE of the denoised image after kAccumulatedFrames frames against the converged reference. Per uniform ray
// count n it reports, for each planning granularity G (AdaptiveRaySettings::granularity and tile):
//   pixel (one count per pixel), tile (the default tile, 8x8 launch cells) and the warp shapes tile8x4, tile4x8:
//   uniform                n rays in every pixel;
//   adaptive_G_equal_rays  the same rays, spent where the denoiser's history is uncertain;
//   adaptive_G_equal_time  a GPU time target equal to the uniform row's pass time (planning included);
//   adaptive_G_budget      (pixel and tile) fractions of the uniform rays (AdaptiveRaySettings::maxRaysPerFrame),
//                          from which the summary interpolates the rays saved at the uniform row's error.
// Then converged tiles (raybridge/converged_tiles.h, default settings), over kConvergedFrames frames, long enough
// for tiles to converge (kDefaultConvergedMinFrames) and then skip:
//   uniform_long           n rays in every pixel;
//   converged_tiles        the same with converged tiles skipped: the rays saved, the time, and the error.
// Per tile against per pixel at equal time is the divergence measurement: a warp traces as long as its busiest
// pixel, so per-pixel counts cost more GPU time than their rays; the 8x4 and 4x8 rows tell which warp shape the
// device's ray generation launch uses (the shape that matches it is as fast as 8x8 and plans more finely).
#include <algorithm>
#include <chrono>
#include <cmath>

#include "effect_sweeps.h"
#include "image_error.h"

namespace rbEffects {

namespace se = sample_engine;
using Stats = rb::HybridStats;

namespace {

// Frames accumulated before the error is measured: the denoiser's history then holds that many frames, which the
// adaptive plan had to work with (the first frame of every run is uniform: no history yet).
constexpr uint32_t kAccumulatedFrames = 8;
// The converged-tile rows: 16 frames to converge, 16 more with tiles skipped (and refreshed once in 8 frames).
constexpr uint32_t kConvergedFrames = 2 * rb::kDefaultConvergedMinFrames;
const double kBudgetFractions[] = {0.25, 0.375, 0.5, 0.625, 0.75, 1.0};

struct Effect {
  std::string name;
  rb::EffectBits flag{};
  const char* passName = "";
  const char* denoiseName = "";
  rb::PassStats Stats::*pass = nullptr;
  rb::PassStats Stats::*denoise = nullptr;
  const char* rawImage = "";
  const char* denoisedImage = "";
  std::function<void(rb::HybridEffectsDesc&, uint32_t)> setRays;
  std::vector<uint32_t> rays;
  uint32_t referenceRays = 0;
  se::FrameParams params;
};

rb::AdaptiveRaySettings& adaptiveOf(rb::HybridEffectsDesc& d, const Effect& fx) {
  return fx.flag == rb::kEffectAo ? d.ao.schedule.adaptive : d.shadows.schedule.adaptive;
}

// A planning granularity the sweep compares (the row names' G).
struct Granularity {
  const char* name;
  rb::AdaptiveRayGranularity granularity;
  uint32_t tileWidth, tileHeight;  // 0 = the SDK's default tile
  bool budgetCurve;                // also the adaptive_G_budget rows
};
const Granularity kGranularities[] = {
    {"pixel", rb::AdaptiveRayGranularity::Pixel, 0, 0, true},
    {"tile", rb::AdaptiveRayGranularity::Tile, 0, 0, true},
    {"tile8x4", rb::AdaptiveRayGranularity::Tile, 8, 4, false},
    {"tile4x8", rb::AdaptiveRayGranularity::Tile, 4, 8, false},
};

// The effect `which` names, with the plan's ray counts and its settings that stay fixed across the rows.
Effect describeEffect(const SweepPlan& plan, rb::EffectBits which, const se::FrameParams& baseParams) {
  Effect fx;
  fx.flag = which;
  fx.params = baseParams;
  fx.rays = plan.adaptiveRays;
  if (which == rb::kEffectAo) {
    fx.name = "ao_adaptive";
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
      d.ao.estimator = rb::AoEstimator::Binary;
    };
    fx.referenceRays = plan.referenceAo;
    return fx;
  }
  fx.name = "shadows_adaptive";
  fx.passName = "shadow";
  fx.denoiseName = "shadow_denoise";
  fx.pass = &Stats::shadow;
  fx.denoise = &Stats::shadowDenoise;
  fx.rawImage = "shadow_raw";
  fx.denoisedImage = "shadow";
  const float radius = plan.sunRadiusDegrees;
  fx.setRays = [radius](rb::HybridEffectsDesc& d, uint32_t n) {
    d.shadows.softAngularRadiusDegrees = radius;
    d.shadows.raysPerPixel = n;
  };
  fx.referenceRays = plan.referenceShadows;
  fx.params.shadow.enabled = false;  // the traced rows read no shadow map
  return fx;
}

// The sweep of one effect: its converged reference, then per uniform ray count the uniform row, the adaptive rows
// of every granularity and the converged-tile rows, each run from a reset history. Rows go into the result as
// they are measured; each ray count adds one entry to the summary.
class AdaptiveSweep {
 public:
  AdaptiveSweep(FrameDriver& driver, Effect fx) : driver_(driver), adapter_(driver.adapter()), fx_(std::move(fx)) {
    result_.effect = fx_.name;
    result_.compared = std::string(fx_.flag == rb::kEffectAo ? "ambient-occlusion open fraction" : "sun visibility") +
                       " after " + std::to_string(kAccumulatedFrames) +
                       " frames of temporal accumulation (denoised, still camera), surface pixels";
    result_.effectMsNote = std::string(fx_.passName) + " + " + fx_.denoiseName +
                           " GPU ms, median over the accumulated frames (adaptive: planning included)";
    adapter_.settings().enabled = true;
  }

  // The raw image averaged over frames of at most kReferenceRaysPerFrame rays, without the denoiser.
  std::string traceReference() {
    rb::HybridEffectsDesc desc;
    desc.effects = fx_.flag;
    desc.shadows.disableDenoiser = desc.ao.disableDenoiser = true;
    fx_.setRays(desc, std::min(fx_.referenceRays, kReferenceRaysPerFrame));
    if (se::Status st = apply(desc); !st) return st.error;
    const uint32_t perFrame = std::min(fx_.referenceRays, kReferenceRaysPerFrame);
    result_.reference.raysPerFrame = perFrame;
    progress("%s: reference, %u rays per pixel", fx_.name.c_str(), fx_.referenceRays);
    const char* rawImage = fx_.rawImage;
    auto ref = rbEffects::traceReference(
        driver_, fx_.params, (fx_.referenceRays + perFrame - 1) / perFrame, 1,
        [rawImage](const rbRender::CapturedFrame& f) -> se::Result<std::vector<float>> {
          auto it = f.images.find(rawImage);
          if (it == f.images.end()) return se::Result<std::vector<float>>::failure("no raw image captured");
          return se::Result<std::vector<float>>::success(it->second);
        },
        fx_.pass, result_.reference);
    if (!ref) return fx_.name + " reference: " + ref.error;
    ref_ = std::move(ref.value);
    result_.surfacePixels = countSet(ref_.mask);
    return {};
  }

  // One uniform ray count n: its row, the adaptive rows per granularity, the converged-tile rows, and the
  // summary entry comparing them.
  std::string sweepRayCount(uint32_t n, nlohmann::json& summary) {
    rb::HybridEffectsDesc d;
    d.effects = fx_.flag;
    fx_.setRays(d, n);
    Row uniform;
    uniform.method = "uniform";
    uniform.setting = std::to_string(n) + " rays";
    uniform.id = "uniform_r" + std::to_string(n);
    uniform.params = {{"rays_per_pixel", n}, {"adaptive", false}};
    if (std::string err = runOnce(d, uniform); !err.empty()) return err;
    const Row u = result_.rows.back();

    nlohmann::json s = {{"rays_per_pixel", n}, {"uniform_rmse", u.rmse}, {"uniform_effect_ms", u.effectMs}};
    std::string line;
    for (const Granularity& g : kGranularities)
      if (std::string err = sweepGranularity(d, n, u, g, s, line); !err.empty()) return err;
    adaptiveOf(d, fx_) = rb::AdaptiveRaySettings{};
    if (std::string err = sweepConvergedTiles(d, n, s, line); !err.empty()) return err;
    summary.push_back(s);
    progress("%s: %u rays: uniform RMSE %.5f (%.3f ms)%s", fx_.name.c_str(), n, u.rmse, u.effectMs, line.c_str());
    return {};
  }

  EffectResult& result() { return result_; }

 private:
  se::Status apply(const rb::HybridEffectsDesc& d) {
    rb::Status st = adapter_.effects().setDesc(d);
    return st ? se::Status::success() : se::Status::failure("HybridEffects::setDesc: " + st.error().message);
  }

  // One run: history reset, `frames` timed frames, then the capture frame's denoised image.
  std::string runOnce(const rb::HybridEffectsDesc& d, Row& row, uint32_t frames = kAccumulatedFrames) {
    if (se::Status st = apply(d); !st) return st.error;
    adapter_.effects().resetHistory();
    auto samples = driver_.run(fx_.params, 0, frames);
    if (!samples) return samples.error;
    auto cap = driver_.capture(fx_.params);
    if (!cap) return cap.error;
    auto it = cap.value.images.find(fx_.denoisedImage);
    if (it == cap.value.images.end()) return std::string("no denoised image captured");
    // Skip the first frames, where the budget controller (with a time target) has not settled yet, or (converged
    // tiles) no tile has converged yet.
    std::vector<FrameSample> settled(samples.value.begin() + frames / 2, samples.value.end());
    const PassResult pass = passMedian(settled, fx_.passName, fx_.pass);
    const PassResult denoise = passMedian(settled, fx_.denoiseName, fx_.denoise);
    row.passes = {pass, denoise};
    row.effectMs = pass.gpuMs + denoise.gpuMs;
    row.effectMsOf = std::string(fx_.passName) + " + " + fx_.denoiseName;
    row.engineMs = engineMedians(settled);
    row.frameMs = row.engineMs["frame"];
    const ErrorStats e = compare(it->second, ref_.values, ref_.mask, 1);
    row.rmse = e.rmse;
    row.bias = e.bias;
    row.params["rays_per_frame"] = pass.rays;
    row.params["rays_per_surface_pixel"] = result_.surfacePixels ? double(pass.rays) / double(result_.surfacePixels)
                                                                 : 0.0;
    row.params["frames"] = frames;
    progress("%s: %-28s %-28s effect %7.3f ms  rays/frame %10llu  RMSE %.5f", fx_.name.c_str(), row.method.c_str(),
             row.setting.c_str(), row.effectMs, static_cast<unsigned long long>(pass.rays), row.rmse);
    result_.rows.push_back(row);
    return {};
  }

  // Granularity g at n rays: the same rays as uniform, then the uniform row's pass time as the target, then (with
  // a budget curve) the budgets. Leaves `d` planning at g, with neither a target nor a budget.
  std::string sweepGranularity(rb::HybridEffectsDesc& d, uint32_t n, const Row& u, const Granularity& g,
                               nlohmann::json& s, std::string& line) {
    rb::AdaptiveRaySettings& a = adaptiveOf(d, fx_);
    a = rb::AdaptiveRaySettings{};
    a.enabled = true;
    a.granularity = g.granularity;
    a.tileWidth = g.tileWidth;
    a.tileHeight = g.tileHeight;
    const std::string method = std::string("adaptive_") + g.name;
    const nlohmann::json common = {{"rays_per_pixel", n}, {"adaptive", true}, {"granularity", g.name}};
    Row equalRays;
    equalRays.method = method + "_equal_rays";
    equalRays.setting = std::to_string(n) + " rays on average";
    equalRays.id = method + "_rays_r" + std::to_string(n);
    equalRays.params = common;
    if (std::string err = runOnce(d, equalRays); !err.empty()) return err;
    const Row r = result_.rows.back();

    a.timeBudgetMs = float(u.passes[0].gpuMs);
    Row equalTime;
    equalTime.method = method + "_equal_time";
    equalTime.setting = "target " + std::to_string(a.timeBudgetMs).substr(0, 6) + " ms";
    equalTime.id = method + "_time_r" + std::to_string(n);
    equalTime.params = common;
    equalTime.params["time_budget_ms"] = a.timeBudgetMs;
    if (std::string err = runOnce(d, equalTime); !err.empty()) return err;
    const Row t = result_.rows.back();
    a.timeBudgetMs = 0.0f;
    s[std::string(g.name) + "_equal_rays_rmse"] = r.rmse;
    s[std::string(g.name) + "_equal_rays_effect_ms"] = r.effectMs;
    s[std::string(g.name) + "_equal_time_rmse"] = t.rmse;
    s[std::string(g.name) + "_equal_time_effect_ms"] = t.effectMs;
    char part[160];
    std::snprintf(part, sizeof part, "; %s %.5f at equal rays (%.3f ms), %.5f at equal time", g.name, r.rmse,
                  r.effectMs, t.rmse);
    line += part;
    if (!g.budgetCurve) return {};
    return sweepBudgets(d, n, u, g, method, common, s, line);
  }

  // Rays saved at equal error: the least budget whose error is no worse than uniform's, interpolated.
  std::string sweepBudgets(rb::HybridEffectsDesc& d, uint32_t n, const Row& u, const Granularity& g,
                           const std::string& method, const nlohmann::json& common, nlohmann::json& s,
                           std::string& line) {
    rb::AdaptiveRaySettings& a = adaptiveOf(d, fx_);
    std::vector<std::pair<double, double>> curve;  // (fraction of the uniform rays, RMSE)
    for (double f : kBudgetFractions) {
      a.maxRaysPerFrame = uint64_t(std::llround(f * n * double(result_.surfacePixels)));
      Row b;
      b.method = method + "_budget";
      b.setting = std::to_string(int(std::lround(f * 100))) + "% of " + std::to_string(n) + " rays";
      b.id = method + "_budget_r" + std::to_string(n) + "_" + std::to_string(int(std::lround(f * 1000)));
      b.params = common;
      b.params["budget_fraction"] = f;
      if (std::string err = runOnce(d, b); !err.empty()) return err;
      curve.push_back({f, result_.rows.back().rmse});
    }
    a.maxRaysPerFrame = 0;
    double fractionAtEqualError = -1.0;  // < 0: even the full budget's error is above uniform's
    for (size_t i = 0; i < curve.size(); ++i) {
      if (curve[i].second <= u.rmse) {
        if (i == 0) {
          fractionAtEqualError = curve[0].first;
        } else {
          const auto [f0, e0] = curve[i - 1];
          const auto [f1, e1] = curve[i];
          fractionAtEqualError = e0 == e1 ? f1 : f0 + (f1 - f0) * (e0 - u.rmse) / (e0 - e1);
        }
        break;
      }
    }
    s[std::string(g.name) + "_budget_fraction_at_equal_error"] = fractionAtEqualError;
    s[std::string(g.name) + "_rays_saved_at_equal_error"] = fractionAtEqualError >= 0.0
                                                                ? nlohmann::json(1.0 - fractionAtEqualError)
                                                                : nlohmann::json(nullptr);
    line += fractionAtEqualError >= 0.0 ? ", rays saved at equal error " +
                                              std::to_string(int(std::lround((1.0 - fractionAtEqualError) * 100))) + "%"
                                        : ", no budget reaches uniform's error";
    return {};
  }

  // Converged tiles against uniform rays over the same kConvergedFrames frames.
  std::string sweepConvergedTiles(rb::HybridEffectsDesc& d, uint32_t n, nlohmann::json& s, std::string& line) {
    Row longUniform;
    longUniform.method = "uniform_long";
    longUniform.setting = std::to_string(n) + " rays, " + std::to_string(kConvergedFrames) + " frames";
    longUniform.id = "uniform_long_r" + std::to_string(n);
    longUniform.params = {{"rays_per_pixel", n}, {"adaptive", false}};
    if (std::string err = runOnce(d, longUniform, kConvergedFrames); !err.empty()) return err;
    const Row lu = result_.rows.back();
    rb::ConvergedTileSettings& c = fx_.flag == rb::kEffectAo ? d.ao.schedule.convergedTiles
                                                             : d.shadows.schedule.convergedTiles;
    c.enabled = true;
    Row converged;
    converged.method = "converged_tiles";
    converged.setting = longUniform.setting;
    converged.id = "converged_tiles_r" + std::to_string(n);
    converged.params = {{"rays_per_pixel", n}, {"adaptive", false}, {"converged_tiles", true}};
    if (std::string err = runOnce(d, converged, kConvergedFrames); !err.empty()) return err;
    const Row ct = result_.rows.back();
    c.enabled = false;
    const double raysSaved = lu.passes[0].rays ? 1.0 - double(ct.passes[0].rays) / double(lu.passes[0].rays) : 0.0;
    s["converged_frames"] = kConvergedFrames;
    s["converged_uniform_rmse"] = lu.rmse;
    s["converged_uniform_effect_ms"] = lu.effectMs;
    s["converged_tiles_rmse"] = ct.rmse;
    s["converged_tiles_effect_ms"] = ct.effectMs;
    s["converged_tiles_rays_saved"] = raysSaved;
    char part[200];
    std::snprintf(part, sizeof part,
                  "; over %u frames uniform %.5f (%.3f ms), converged tiles %.5f (%.3f ms, %d%% of the rays saved)",
                  kConvergedFrames, lu.rmse, lu.effectMs, ct.rmse, ct.effectMs, int(std::lround(raysSaved * 100)));
    line += part;
    return {};
  }

  FrameDriver& driver_;
  rbAdapter::Adapter& adapter_;
  Effect fx_;
  EffectResult result_;
  ReferenceImage ref_;
};

}  // namespace

se::Result<EffectResult> runAdaptiveSweep(FrameDriver& driver, const SweepPlan& plan, rb::EffectBits which) {
  using R = se::Result<EffectResult>;
  const auto start = std::chrono::steady_clock::now();
  AdaptiveSweep sweep(driver, describeEffect(plan, which, driver.baseParams()));
  if (std::string err = sweep.traceReference(); !err.empty()) return R::failure(err);
  nlohmann::json summary = nlohmann::json::array();
  for (uint32_t n : plan.adaptiveRays)
    if (std::string err = sweep.sweepRayCount(n, summary); !err.empty()) return R::failure(err);
  EffectResult& result = sweep.result();
  result.summary = summary;
  result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return R::success(std::move(result));
}

}  // namespace rbEffects
