// --scenario motion (see the header). Order of work: every case's references first (the passes at many rays, no
// denoiser, the scene frozen at each measured frame), then, per ray count, each case's sequence with the denoisers on
// (histories reset first) and, where a metric needs one, its control: the same frames with the scene and camera
// already at rest in their final state, so that "the still-frame error" is measured on the same pixels at the same
// frame and noise.
#include "motion_sweep.h"

#include <glm/gtc/matrix_transform.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <functional>
#include <map>

#include "image_error.h"
#include "motion_metrics.h"
#include "reset_follow_up.h"
#include "sweep_common.h"

namespace rbEffects {

namespace se = sample_engine;

namespace {

struct MotionEffect {
  std::string name;
  rb::EffectBits flag{};
  const char* raw = "";  // FrameDriver::capture names
  const char* denoised = "";
  bool rgb = false;
  rb::PassStats rb::HybridStats::*pass = nullptr;
  rb::PassStats rb::HybridStats::*denoise = nullptr;
};
using HS = rb::HybridStats;
const MotionEffect kEffects[] = {
    {"shadows", rb::kEffectShadows, "shadow_raw", "shadow", false, &HS::shadow, &HS::shadowDenoise},
    {"ao", rb::kEffectAo, "ao_raw", "ao", false, &HS::ao, &HS::aoDenoise},
    {"reflections", rb::kEffectReflections, "reflection_raw", "reflection", true, &HS::reflection,
     &HS::reflectionDenoise},
    {"local_lights", rb::kEffectLocalLights, "lights_raw", "lights", true, &HS::localLights, &HS::localLightsDenoise}};
// A pixel's converged value changed: by 0.2 of visibility / open fraction, or 20% of the frame's mean colour (the
// references' own noise, 256 rays at p = 0.5: 0.03 a pixel, 0.044 between two frames, stays well under it).
constexpr float kChangeThreshold = 0.2f;
// Lag: the changed pixels' error is back when it is within this factor of the still sequence's.
constexpr double kLagFactor = 1.5;
// An RMSE below this is no error: the rounding of the half-float outputs. Where the still sequence's error is 0 (the
// local lights traced exactly at 4 and more rays), the moved one is back once it is below this too; until 2026-12-06
// a still error of 0 gave a ratio of 0, read as "lag 0" however wrong the moved frames were.
constexpr double kErrorFloor = 1e-4;

// The moved sequence's error over the still one's, each at least kErrorFloor.
double errorRatio(double moved, double still) { return std::max(moved, kErrorFloor) / std::max(still, kErrorFloor); }

enum class Kind { Still, Camera, Event, Steady };

struct Case {
  std::string name;
  Kind kind = Kind::Still;
  std::string what;
  std::function<se::FrameParams(uint32_t)> at;  // frame k of warmup + measured
  // Every case but the still one has a control: its last frame's state held from the first frame on.
  bool hasControl() const { return kind != Kind::Still; }
};

// One captured frame, reduced to what the metrics read.
struct Frame {
  std::vector<float> viewDepth;
  std::vector<uint8_t> surface;
  std::vector<glm::vec2> motion;
  std::map<std::string, EffectFrame> effects;  // "<effect>" (denoised) and "<effect>_raw"
  rb::HybridStats stats;                       // the frame's GPU ms and rays per pass
};

se::Result<EffectFrame> extract(const rbRender::CapturedFrame& f, const char* name, bool rgb) {
  auto it = f.images.find(name);
  if (it == f.images.end()) return se::Result<EffectFrame>::failure(std::string("no captured '") + name + "' image");
  return se::Result<EffectFrame>::success(rgb ? EffectFrame{rgbOf(it->second), 3} : EffectFrame{it->second, 1});
}

class Runner {
 public:
  Runner(FrameDriver& driver, const MotionScene& scene, const MotionPlan& plan)
      : driver_(driver), scene_(scene), plan_(plan) {}

  se::Result<nlohmann::json> run();

 private:
  std::vector<Case> makeCases() const;
  std::vector<MotionEffect> effects() const {
    std::vector<MotionEffect> out;
    for (const MotionEffect& e : kEffects)
      if (plan_.effects & e.flag) out.push_back(e);
    return out;
  }
  se::Status setDesc(uint32_t rays, bool reference);
  se::Result<Frame> capture(const se::FrameParams& params, bool withOutputs);
  se::Result<std::vector<Frame>> references(const Case& c);
  // Renders frames 0 .. warmup + measured - 1 of `at` from a reset history, capturing the measured frames for which
  // `keep` says so (others get an empty Frame).
  se::Result<std::vector<Frame>> sequence(const std::function<se::FrameParams(uint32_t)>& at,
                                          const std::function<bool(uint32_t)>& keep);
  se::Status writeStrip(const Case& c, const std::vector<Frame>& refs, const std::vector<Frame>& frames);
  nlohmann::json score(const Case& c, const MotionEffect& e, const std::vector<Frame>& refs,
                       const std::vector<Frame>& frames, const std::vector<Frame>& control);

  FrameDriver& driver_;
  const MotionScene& scene_;
  const MotionPlan& plan_;
};

std::vector<Case> Runner::makeCases() const {
  const se::FrameParams base = driver_.baseParams();
  const uint32_t last = plan_.warmupFrames + plan_.measuredFrames - 1;
  const double fps = plan_.fps;
  auto still = [base](uint32_t) {
    se::FrameParams p = base;
    p.restPose = true;
    return p;
  };
  std::vector<Case> cases;
  cases.push_back({"still", Kind::Still, "camera and scene at rest", still});
  // Pan: the camera slides sideways 2 cm a frame (0.6 m/s at 30 fps); ends on the scene's camera.
  auto pan = [base, last](uint32_t k) {
    se::FrameParams p = base;
    p.restPose = true;
    const glm::vec3 forward = glm::normalize(base.camera.target - base.camera.eye);
    const glm::vec3 right = glm::normalize(glm::cross(forward, glm::vec3(0, 1, 0)));
    const glm::vec3 offset = right * (0.02f * (float(k) - float(last)));
    p.camera.eye += offset;
    p.camera.target += offset;
    return p;
  };
  cases.push_back({"pan", Kind::Camera, "camera slides sideways 0.02 m per frame", pan});
  // Turn: the camera yaws 2 degrees a frame (60 degrees/s at 30 fps) about its eye.
  auto turn = [base, last](uint32_t k) {
    se::FrameParams p = base;
    p.restPose = true;
    const float angle = glm::radians(2.0f * (float(k) - float(last)));
    const glm::mat4 r = glm::rotate(glm::mat4(1.0f), angle, glm::vec3(0, 1, 0));
    p.camera.target = base.camera.eye + glm::vec3(r * glm::vec4(base.camera.target - base.camera.eye, 0.0f));
    return p;
  };
  cases.push_back({"turn", Kind::Camera, "camera turns 2 degrees per frame", turn});
  if (!scene_.walkers.empty()) {
    auto walk = [base, fps, walkers = scene_.walkers](uint32_t k) {
      se::FrameParams p = base;
      p.animations = walkers;
      p.time = 1.0 + double(k) / fps;
      return p;
    };
    cases.push_back({"walkers", Kind::Steady, "skinned characters walk: " + scene_.walkersNote, walk});
  }
  // Events: the animation's STEP key falls on measured frame eventFrame.
  const uint32_t event = plan_.warmupFrames + plan_.eventFrame;
  auto eventCase = [&](const char* name, const char* what, uint32_t animation) {
    auto at = [base, fps, event, animation](uint32_t k) {
      se::FrameParams p = base;
      p.animations = {{animation, 0.0}};
      p.time = std::max(0.0, kMotionEventTime + (double(k) - double(event)) / fps);
      return p;
    };
    cases.push_back({name, Kind::Event, what, at});
  };
  eventCase("teleport", "a pillar jumps 4 m across the ground in front of the mirror", scene_.teleportAnimation);
  eventCase("lamp_jump", "a point lamp jumps 5 m", scene_.lampAnimation);
  auto door = [base, fps, animation = scene_.doorAnimation](uint32_t k) {
    se::FrameParams p = base;
    p.animations = {{animation, 0.0}};
    p.time = 0.5 + double(k) / fps;
    return p;
  };
  cases.push_back({"door", Kind::Steady, "a door swings 30 degrees per second", door});
  return cases;
}

se::Status Runner::setDesc(uint32_t rays, bool reference) {
  rb::HybridEffectsDesc d;
  d.effects = plan_.effects;
  d.shadows.raysPerPixel = rays;
  d.shadows.softAngularRadiusDegrees = 0.5f;
  d.shadows.disableDenoiser = reference;
  d.ao.raysPerPixel = rays;
  d.ao.estimator = rb::AoEstimator::Binary;
  d.ao.disableDenoiser = reference;
  d.reflections.raysPerPixel = rays;
  d.reflections.disableDenoiser = reference;
  d.localLights.raysPerPixel = rays;
  d.localLights.disableDenoiser = reference;
  d.denoiser.disableAntiLag = plan_.switches.disableAntiLag;
  d.ao.disableShortHistoryFilter = plan_.switches.disableShortHistoryFilter;
  d.ao.disableResetRays = plan_.switches.disableResetRays;
  d.shadows.disableResetRays = plan_.switches.disableResetRays;
  d.reflections.disableRelitResets = plan_.switches.noReflectionChanges;
  if (plan_.switches.resetRaysFactor && !reference) {
    d.shadows.schedule.resetRays = plan_.switches.resetRaysFactor * rays;
    d.ao.schedule.resetRays = plan_.switches.resetRaysFactor * rays;
  }
  d.disableChangeResets = plan_.switches.disableChangeResets;
  rbTools::applyResetFollowUp(d, plan_.switches.resetFollowUp);
  if (plan_.switches.convergedTiles && !reference) {
    d.shadows.schedule.convergedTiles.enabled = true;
    d.ao.schedule.convergedTiles.enabled = true;
    d.reflections.schedule.convergedTiles.enabled = true;
    d.localLights.schedule.convergedTiles.enabled = true;
  }
  // The local lights' reference is exact (one ray per light and pixel): no noise to accumulate.
  if (reference) d.localLights.mode = rb::ManyLightMode::Exact;
  rb::Status st = driver_.adapter().effects().setDesc(d);
  return st ? se::Status::success() : se::Status::failure("HybridEffects::setDesc: " + st.error().message);
}

se::Result<Frame> Runner::capture(const se::FrameParams& params, bool withOutputs) {
  using R = se::Result<Frame>;
  FrameSample sample;
  auto cap = driver_.capture(params, &sample);
  if (!cap) return R::failure(cap.error);
  Frame f;
  f.stats = sample.passes;
  f.surface = surfaceMask(cap.value.depth);
  f.viewDepth = viewDepth(cap.value.depth, params.camera.zNear, params.camera.zFar, false);
  auto mv = driver_.engine().readbackMotionVectors();
  if (!mv) return R::failure("readbackMotionVectors: " + mv.error);
  f.motion = std::move(mv.value);
  for (const MotionEffect& e : effects()) {
    auto raw = extract(cap.value, e.raw, e.rgb);
    if (!raw) return R::failure(raw.error);
    f.effects[e.name + "_raw"] = std::move(raw.value);
    if (!withOutputs) continue;
    auto out = extract(cap.value, e.denoised, e.rgb);
    if (!out) return R::failure(out.error);
    f.effects[e.name] = std::move(out.value);
  }
  return R::success(std::move(f));
}

se::Result<std::vector<Frame>> Runner::references(const Case& c) {
  using R = se::Result<std::vector<Frame>>;
  std::vector<Frame> refs;
  for (uint32_t j = 0; j < plan_.measuredFrames; ++j) {
    const se::FrameParams p = c.at(plan_.warmupFrames + j);
    // One untimed frame first: a deforming mesh's BLAS and the TLAS settle at this pose.
    if (auto warm = driver_.run(p, 1, 0); !warm) return R::failure(warm.error);
    std::map<std::string, Accumulator> acc;
    Frame ref;
    for (uint32_t r = 0; r < plan_.referenceFrames; ++r) {
      auto f = capture(p, false);
      if (!f) return R::failure(f.error);
      for (auto& [name, e] : f.value.effects) acc[name].add(e.values);
      if (r == 0) ref = std::move(f.value);
    }
    for (const MotionEffect& e : effects()) {
      EffectFrame& raw = ref.effects[e.name + "_raw"];
      ref.effects[e.name] = {acc[e.name + "_raw"].mean(), raw.channels};
      ref.effects.erase(e.name + "_raw");
    }
    refs.push_back(std::move(ref));
  }
  return R::success(std::move(refs));
}

se::Result<std::vector<Frame>> Runner::sequence(const std::function<se::FrameParams(uint32_t)>& at,
                                                const std::function<bool(uint32_t)>& keep) {
  using R = se::Result<std::vector<Frame>>;
  driver_.adapter().effects().resetHistory();
  std::vector<Frame> frames(plan_.measuredFrames);
  for (uint32_t k = 0; k < plan_.warmupFrames + plan_.measuredFrames; ++k) {
    const se::FrameParams p = at(k);
    const bool measured = k >= plan_.warmupFrames;
    if (measured && keep(k - plan_.warmupFrames)) {
      auto f = capture(p, true);
      if (!f) return R::failure(f.error);
      frames[k - plan_.warmupFrames] = std::move(f.value);
    } else if (auto r = driver_.run(p, 1, 0); !r) {
      return R::failure(r.error);
    }
  }
  return R::success(std::move(frames));
}

double mean(const std::vector<double>& v) {
  double s = 0.0;
  for (double x : v) s += x;
  return v.empty() ? 0.0 : s / double(v.size());
}

nlohmann::json Runner::score(const Case& c, const MotionEffect& e, const std::vector<Frame>& refs,
                             const std::vector<Frame>& frames, const std::vector<Frame>& control) {
  const uint32_t m = plan_.measuredFrames;
  const uint32_t w = plan_.width, h = plan_.height;
  std::vector<double> all, raw, changed, disoccluded, flickerOut, flickerRef, passMs, denoiseMs, passRays;
  std::vector<uint64_t> changedCount, disoccludedCount;
  // changedMask[j]: frame j's pixels whose reference changed since frame j - 1 (none for frame 0); the event and
  // steady summaries below read it at their frames.
  std::vector<std::vector<uint8_t>> changedMask(m);
  for (uint32_t j = 0; j < m; ++j) {
    const Frame& f = frames[j];
    const Frame& r = refs[j];
    all.push_back(rmseOver(f.effects.at(e.name), r.effects.at(e.name), f.surface));
    passMs.push_back((f.stats.*e.pass).gpuMs);
    denoiseMs.push_back((f.stats.*e.denoise).gpuMs);
    passRays.push_back(double((f.stats.*e.pass).rays));  // reset rays add to it in the frames with a change
    raw.push_back(rmseOver(f.effects.at(e.name + "_raw"), r.effects.at(e.name), f.surface));
    if (j == 0) continue;
    const std::vector<uint8_t> surfaces = both(f.surface, frames[j - 1].surface);
    changedMask[j] = changedPixels(refs[j - 1].effects.at(e.name), r.effects.at(e.name), surfaces, kChangeThreshold);
    const std::vector<uint8_t>& ch = changedMask[j];
    const std::vector<uint8_t> dis = disoccludedPixels(f.viewDepth, frames[j - 1].viewDepth, f.motion, f.surface, w, h);
    changedCount.push_back(count(ch));
    disoccludedCount.push_back(count(dis));
    changed.push_back(rmseOver(f.effects.at(e.name), r.effects.at(e.name), ch));
    disoccluded.push_back(rmseOver(f.effects.at(e.name), r.effects.at(e.name), dis));
    flickerOut.push_back(meanAbsoluteChange(f.effects.at(e.name), frames[j - 1].effects.at(e.name), surfaces));
    flickerRef.push_back(meanAbsoluteChange(r.effects.at(e.name), refs[j - 1].effects.at(e.name), surfaces));
  }
  nlohmann::json j = {{"rmse", all},
                      {"rmse_raw", raw},
                      {"rmse_changed", changed},
                      {"changed_pixels", changedCount},
                      {"rmse_disoccluded", disoccluded},
                      {"disoccluded_pixels", disoccludedCount},
                      {"flicker", flickerOut},
                      {"flicker_reference", flickerRef},
                      {"pass_gpu_ms_median", median(passMs)},
                      {"denoise_gpu_ms_median", median(denoiseMs)},
                      {"pass_rays", passRays},
                      {"pass_rays_mean", mean(passRays)},
                      {"rmse_mean", mean(all)},
                      {"rmse_raw_mean", mean(raw)}};
  const double fo = mean(flickerOut), fr = mean(flickerRef);
  j["flicker_mean"] = fo;
  j["flicker_reference_mean"] = fr;
  j["flicker_ratio"] = fr > 0.0 ? nlohmann::json(fo / fr) : nlohmann::json(nullptr);
  j["disocclusion_rmse_mean"] = mean(disoccluded);
  if (c.kind == Kind::Event) {
    // The pixels the event changed (reference before vs after it), followed frame by frame against the control.
    const uint32_t ev = plan_.eventFrame;
    const std::vector<uint8_t>& ch = changedMask[ev];
    std::vector<double> moved, still, ratio;
    nlohmann::json lag = nullptr;
    for (uint32_t k = ev; k < m; ++k) {
      moved.push_back(rmseOver(frames[k].effects.at(e.name), refs[k].effects.at(e.name), ch));
      still.push_back(rmseOver(control[k].effects.at(e.name), refs[k].effects.at(e.name), ch));
      ratio.push_back(errorRatio(moved.back(), still.back()));
      if (lag.is_null() && ratio.back() <= kLagFactor) lag = k - ev;
    }
    j["event"] = {{"changed_pixels", count(ch)},
                  {"rmse_changed_after_event", moved},
                  {"rmse_changed_still", still},
                  {"ratio", ratio},
                  {"lag_frames", lag}};
  } else if (c.kind == Kind::Steady || c.kind == Kind::Camera) {
    // The last frame against the same frame of a sequence that was at rest there all along: the changed pixels
    // (steady motion) or every surface pixel (camera motion).
    const uint32_t last = m - 1;
    const std::vector<uint8_t>& pixels = c.kind == Kind::Steady ? changedMask[last] : frames[last].surface;
    const double moving = rmseOver(frames[last].effects.at(e.name), refs[last].effects.at(e.name), pixels);
    const double rest = rmseOver(control[last].effects.at(e.name), refs[last].effects.at(e.name), pixels);
    j["steady"] = {{"pixels", count(pixels)},
                   {"rmse_moving", moving},
                   {"rmse_at_rest", rest},
                   {"ratio", errorRatio(moving, rest)}};
  }
  return j;
}

se::Status Runner::writeStrip(const Case& c, const std::vector<Frame>& refs, const std::vector<Frame>& frames) {
  const uint32_t w = plan_.width, h = plan_.height;
  for (const MotionEffect& e : effects()) {
    for (uint32_t j = plan_.eventFrame - 1; j < std::min(plan_.measuredFrames, plan_.eventFrame + 3); ++j) {
      const std::pair<const char*, const EffectFrame*> images[] = {{"raw", &frames[j].effects.at(e.name + "_raw")},
                                                                   {"denoised", &frames[j].effects.at(e.name)},
                                                                   {"reference", &refs[j].effects.at(e.name)}};
      for (const auto& [kind, image] : images) {
        const std::string id = c.name + "_" + kind + "_f" + std::to_string(int(j) - int(plan_.eventFrame));
        const EffectFrame* img = image;  // Clang before 16 cannot capture a structured binding
        SweepPlan sp;
        sp.imagesDir = plan_.imagesDir;
        auto written = writeImage(sp, "motion/" + e.name, id, [&](const std::string& path) {
          return e.rgb ? writeTonemappedPng(path, img->values, w, h, 1.0f) : writeGreyPng(path, img->values, w, h);
        });
        if (!written) return se::Status::failure(written.error);
      }
    }
  }
  return se::Status::success();
}

se::Result<nlohmann::json> Runner::run() {
  using R = se::Result<nlohmann::json>;
  if (plan_.eventFrame < 1 || plan_.eventFrame + 1 >= plan_.measuredFrames)
    return R::failure("motion: the event frame must have a measured frame before and after it");
  progress("motion scene: %s", scene_.walkersNote.c_str());
  const std::vector<Case> cases = makeCases();
  nlohmann::json out;
  out["cases"] = nlohmann::json::array();
  for (const Case& c : cases) {
    if (!plan_.cases.empty() && std::find(plan_.cases.begin(), plan_.cases.end(), c.name) == plan_.cases.end())
      continue;
    const auto start = std::chrono::steady_clock::now();
    if (se::Status st = setDesc(plan_.referenceRaysPerFrame, true); !st) return R::failure(st.error);
    progress("motion: %s: references, %u frames of %u rays per measured frame", c.name.c_str(), plan_.referenceFrames,
             plan_.referenceRaysPerFrame);
    auto refs = references(c);
    if (!refs) return R::failure(c.name + " reference: " + refs.error);
    nlohmann::json jc = {{"name", c.name}, {"what", c.what}, {"rays", nlohmann::json::object()}};
    for (uint32_t n : plan_.rays) {
      if (se::Status st = setDesc(n, false); !st) return R::failure(st.error);
      auto frames = sequence(c.at, [](uint32_t) { return true; });
      if (!frames) return R::failure(c.name + ": " + frames.error);
      std::vector<Frame> control;
      if (c.hasControl()) {
        const uint32_t last = plan_.measuredFrames - 1;
        const uint32_t ev = plan_.eventFrame;
        const bool event = c.kind == Kind::Event;
        const se::FrameParams atRest = c.at(plan_.warmupFrames + last);
        auto ctl = sequence([&](uint32_t) { return atRest; }, [&](uint32_t j) { return event ? j >= ev : j == last; });
        if (!ctl) return R::failure(c.name + " control: " + ctl.error);
        control = std::move(ctl.value);
      }
      nlohmann::json je;
      for (const MotionEffect& e : effects()) {
        je[e.name] = score(c, e, refs.value, frames.value, control);
        const nlohmann::json& s = je[e.name];
        std::string summary;
        char buf[160];
        if (s.contains("event")) {
          std::snprintf(buf, sizeof buf, "lag %s frames, changed RMSE at the event %.4f (still %.4f)",
                        s["event"]["lag_frames"].is_null() ? "> all" : s["event"]["lag_frames"].dump().c_str(),
                        s["event"]["rmse_changed_after_event"][0].get<double>(),
                        s["event"]["rmse_changed_still"][0].get<double>());
          summary = buf;
        } else if (s.contains("steady")) {
          std::snprintf(buf, sizeof buf, "moving/at rest %.2f",
                        s["steady"]["ratio"].is_null() ? 0.0 : s["steady"]["ratio"].get<double>());
          summary = buf;
        }
        progress("motion: %-9s %2u rays %-12s RMSE %.4f (raw %.4f)  flicker %.5f (ref %.5f)  %s", c.name.c_str(), n,
                 e.name.c_str(), s["rmse_mean"].get<double>(), s["rmse_raw_mean"].get<double>(),
                 s["flicker_mean"].get<double>(), s["flicker_reference_mean"].get<double>(), summary.c_str());
      }
      jc["rays"][std::to_string(n)] = je;
      // The change masks' GPU time, on the measured frames that recorded them (frames with a known change).
      std::vector<double> maskMs;
      for (const Frame& f : frames.value) {
        const rb::HybridStats& st = f.stats;
        const uint64_t frame = std::max({st.shadow.frame, st.ao.frame, st.reflection.frame, st.localLights.frame});
        if (st.changeMasks.frame != 0 && st.changeMasks.frame == frame) maskMs.push_back(st.changeMasks.gpuMs);
      }
      jc["change_masks_gpu_ms_median"][std::to_string(n)] = maskMs.empty() ? nlohmann::json(nullptr)
                                                                           : nlohmann::json(median(maskMs));
      jc["change_masks_frames"][std::to_string(n)] = maskMs.size();
      if (n == plan_.stripRays && c.name == "teleport" && !plan_.imagesDir.empty()) {
        if (se::Status st = writeStrip(c, refs.value, frames.value); !st) return R::failure(st.error);
      }
    }
    jc["seconds"] = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    out["cases"].push_back(std::move(jc));
  }
  return R::success(std::move(out));
}

}  // namespace

MotionPlan makeMotionPlan(bool quick, uint32_t width, uint32_t height, rb::EffectSet effects, const std::string& images,
                          const MotionSwitches& switches, const std::vector<uint32_t>& rays) {
  MotionPlan mp;
  mp.width = width;
  mp.height = height;
  mp.effects = effects;
  mp.imagesDir = images;
  mp.switches = switches;
  if (quick) {
    mp.warmupFrames = 3;
    mp.measuredFrames = 4;
    mp.eventFrame = 1;
    mp.referenceFrames = 2;
    mp.referenceRaysPerFrame = 16;
    mp.rays = {4};
  }
  if (!rays.empty()) mp.rays = rays;
  mp.stripRays = mp.rays.size() > 1 ? mp.rays[1] : mp.rays[0];
  return mp;
}

std::vector<std::string> motionChecks(const nlohmann::json& motion, uint64_t pixels) {
  std::vector<std::string> failures;
  for (const nlohmann::json& c : motion["cases"]) {
    for (auto& [rays, effects] : c["rays"].items()) {
      for (auto& [effect, e] : effects.items()) {
        const std::string at = c["name"].get<std::string>() + ", " + effect + ", " + rays + " rays";
        if (c["name"] == "teleport" && effect != "local_lights" && e["event"]["changed_pixels"].get<uint64_t>() == 0)
          failures.push_back(at + ": the teleport changed no pixel of the reference");
        if (c["name"] == "still")
          for (const nlohmann::json& n : e["changed_pixels"])
            if (double(n.get<uint64_t>()) > 0.02 * double(pixels))
              failures.push_back(at + ": the still reference changed in " + n.dump() + " pixels");
      }
    }
  }
  return failures;
}

se::Result<nlohmann::json> runMotionScenario(FrameDriver& driver, const MotionScene& scene, const MotionPlan& plan) {
  Runner runner(driver, scene, plan);
  auto r = runner.run();
  if (!r) return r;
  nlohmann::json& j = r.value;
  j["plan"] = {{"warmup_frames", plan.warmupFrames},
               {"measured_frames", plan.measuredFrames},
               {"event_frame", plan.eventFrame},
               {"reference_frames", plan.referenceFrames},
               {"reference_rays_per_frame", plan.referenceRaysPerFrame},
               {"local_lights_reference", "Exact mode (one ray per light and pixel)"},
               {"rays", plan.rays},
               {"fps", plan.fps},
               {"change_threshold", kChangeThreshold},
               {"lag_factor", kLagFactor},
               {"anti_lag", !plan.switches.disableAntiLag},
               {"change_resets", !plan.switches.disableChangeResets},
               {"converged_tiles", plan.switches.convergedTiles},
               {"short_history_filter", !plan.switches.disableShortHistoryFilter},
               {"reset_rays", !plan.switches.disableResetRays},
               {"reflection_relit_resets", !plan.switches.noReflectionChanges},
               {"reset_rays_factor", plan.switches.disableResetRays  ? 0u
                                     : plan.switches.resetRaysFactor ? plan.switches.resetRaysFactor
                                                                     : rb::kDefaultResetRaysFactor},
               {"reset_follow_up_frames", plan.switches.disableResetRays ? 0u
                                          : plan.switches.resetFollowUp  ? *plan.switches.resetFollowUp
                                                                         : rb::kDefaultResetFollowUpFrames}};
  return r;
}

}  // namespace rbEffects
