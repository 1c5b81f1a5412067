// raybridge-effects-bench: speed against error of each ray-traced effect (Raybridge through the sample engine's
// adapter) and of its raster counterpart in the engine, measured against a converged reference that Raybridge
// traces itself. Scenario "speed-vs-error" (the only one): see effect_sweeps.h and docs/effects.md.
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <fstream>

#include "effect_sweeps.h"
#include "effects_bench_options.h"
#include "motion_sweep.h"
#include "report.h"

namespace se = sample_engine;
using namespace rbEffects;

namespace {

int fail(const std::string& message, int code = 1) {
  std::fprintf(stderr, "raybridge-effects-bench: error: %s\n", message.c_str());
  return code;
}

std::string utcNow() {
  const std::time_t t = std::time(nullptr);
  char buf[32];
  std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%SZ", std::gmtime(&t));
  return buf;
}

nlohmann::json vec(const glm::vec3& v) { return {v.x, v.y, v.z}; }

// The settings each sweep visits. Full: the lists. Quick (the ctest smoke run): two of each, so that the
// self-checks still have a "fewest" and a "most" row, in well under a minute with validation on lavapipe.
// The mechanisms the motion scenario's command line turns off or on.
MotionSwitches switchesOf(const Options& o) {
  return {o.noAntiLag,   o.noChangeResets,  o.convergedTiles,      o.noShortHistoryFilter,
          o.noResetRays, o.resetRaysFactor, o.noReflectionChanges, o.resetFollowUp};
}

SweepPlan makePlan(const Options& o, bool cpu, uint32_t width, uint32_t height) {
  SweepPlan p;
  p.width = width;
  p.height = height;
  p.imagesDir = o.images;
  p.aoRange = o.aoRange;
  p.reflectionRoughness = o.reflectionRoughness;
  p.warmupFrames = o.quick ? 1 : 2;
  p.timedFrames = o.timedFrames.value_or(o.quick ? 2 : (cpu ? 3 : 7));
  if (o.quick) {
    p.shadowRays = {1, 16};
    p.aoRays = {1, 16};
    p.reflectionRays = {1, 8};
    p.adaptiveRays = {4};
    p.shadowMaps = {{1024, 1}, {2048, 5}};
    p.ssaoKernels = {8, 32};
    p.probeSizes = {0, 64};
  } else {
    p.shadowRays = {1, 2, 4, 8, 16, 32};
    p.aoRays = {1, 2, 4, 8, 16, 32};
    p.reflectionRays = {1, 2, 4, 8};
    p.adaptiveRays = {2, 4, 8};
    for (uint32_t size : {1024u, 2048u, 4096u, 8192u})
      for (uint32_t pcf : {1u, 3u, 5u, 7u}) p.shadowMaps.push_back({size, pcf});
    p.ssaoKernels = {8, 16, 32, 64};
    p.probeSizes = {0, 64, 128, 256};
  }
  // Reference rays per pixel: on a GPU enough that the reference's noise is far below the best traced row's
  // error; on a CPU device as many as fit the ~10-minute budget at 320x180.
  const uint32_t shadows = o.quick ? 512 : (cpu ? 2048 : 4096);
  const uint32_t reflections = o.quick ? 256 : (cpu ? 1024 : 2048);
  p.referenceShadows = o.referenceRaysShadows.value_or(shadows);
  p.referenceAo = o.referenceRaysAo.value_or(shadows);
  p.referenceReflections = o.referenceRaysReflections.value_or(reflections);
  return p;
}

}  // namespace

int main(int argc, char** argv) {
  Options o;
  if (std::string e = parseOptions(argc, argv, o); !e.empty()) {
    std::fprintf(stderr, "%s", usage());
    return fail(e, 2);
  }
  if (o.help) return std::printf("%s", usage()), 0;
  if (const char* v = std::getenv("RAYBRIDGE_VALIDATION"); v && std::string(v) == "1") o.validation = true;
  // A missing raw rate costs only the fractions: on the GPU machine the bench runs once, after raybridge-bench,
  // and must not lose its measurements because that step failed.
  std::optional<RawRate> raw;
  std::string rawRateError;
  if (RawRate r; !o.rawRateJson.empty()) {
    if (rawRateError = readRawRate(o.rawRateJson, r); rawRateError.empty()) raw = r;
    else
      std::fprintf(stderr, "raybridge-effects-bench: warning: %s; rays/s are reported without fractions\n",
                   rawRateError.c_str());
  }
  const auto start = std::chrono::steady_clock::now();

  FrameDriver::Config dc;
  dc.device = o.device;
  dc.validation = o.validation;
  const bool motion = o.scenario == "motion";
  MotionScene motionScene;
  if (motion) {
    motionScene = makeMotionScene(o.scenes.empty() ? RAYBRIDGE_SOURCE_DIR "/../shared/scenes" : o.scenes, o.characters);
    dc.scene = motionScene.scene;
  }
  auto created = FrameDriver::create(dc);
  if (!created) return fail(created.error);
  FrameDriver& driver = *created.value;
  const rb::DeviceInfo& di = driver.adapter().context().deviceInfo();
  const bool cpu = di.isCpu;
  const uint32_t width = o.width.value_or(o.quick ? 160 : (cpu ? 320 : 1920));
  const uint32_t height = o.height.value_or(o.quick ? 90 : (cpu ? 180 : 1080));
  if (se::Status s = driver.setRenderSize(width, height); !s) return fail(s.error);
  const SweepPlan plan = makePlan(o, cpu, width, height);
  std::printf("raybridge-effects-bench on %s (%s %s), %ux%u%s, median of %u frames after %u warm-up\n",
              di.deviceName.c_str(), di.driverName.c_str(), di.driverInfo.c_str(), width, height,
              o.quick ? " [--quick]" : "", plan.timedFrames, plan.warmupFrames);
  std::fflush(stdout);

  std::vector<EffectResult> results;
  using Sweep = se::Result<EffectResult> (*)(FrameDriver&, const SweepPlan&);
  const std::pair<rb::EffectBits, Sweep> sweeps[] = {{rb::kEffectShadows, runShadowSweep},
                                                     {rb::kEffectAo, runAoSweep},
                                                     {rb::kEffectReflections, runReflectionSweep}};
  nlohmann::json motionResult;
  if (motion) {
    MotionPlan motionPlan = makeMotionPlan(o.quick, width, height, o.effects, o.images, switchesOf(o), o.motionRays);
    motionPlan.cases = o.motionCases;
    auto m = runMotionScenario(driver, motionScene, motionPlan);
    if (!m) return fail(m.error);
    motionResult = std::move(m.value);
  }
  for (auto [flag, sweep] : sweeps) {
    if (motion || !(o.effects & flag)) continue;
    if (o.scenario == "adaptive" && flag == rb::kEffectReflections) continue;  // adaptive rays: shadows and AO
    auto r = o.scenario == "adaptive" ? runAdaptiveSweep(driver, plan, flag) : sweep(driver, plan);
    if (!r) return fail(r.error);
    results.push_back(std::move(r.value));
  }
  if (!motion) printTables(results, raw);

  const se::FrameParams& base = driver.baseParams();
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  nlohmann::json doc;
  doc["tool"] = "raybridge-effects-bench";
  doc["scenario"] = o.scenario;
  doc["date"] = utcNow();
  doc["command_line"] = o.commandLine;
  doc["device"] = {{"name", di.deviceName},
                   {"driver", di.driverName},
                   {"driver_info", di.driverInfo},
                   {"api_version", std::to_string(VK_API_VERSION_MAJOR(di.apiVersion)) + "." +
                                       std::to_string(VK_API_VERSION_MINOR(di.apiVersion)) + "." +
                                       std::to_string(VK_API_VERSION_PATCH(di.apiVersion))},
                   {"is_cpu", cpu}};
  doc["width"] = width;
  doc["height"] = height;
  doc["quick"] = o.quick;
  doc["scene"] = {{"name", "sample engine default demo scene (makeDefaultDemoScene)"},
                  {"camera",
                   {{"eye", vec(base.camera.eye)},
                    {"target", vec(base.camera.target)},
                    {"fovy_degrees", base.camera.fovYDegrees},
                    {"z_near", base.camera.zNear},
                    {"z_far", base.camera.zFar}}},
                  {"sun",
                   {{"direction", vec(base.sun.direction)},
                    {"radiance", vec(base.sun.color * base.sun.intensity)},
                    {"angular_radius_degrees", plan.sunRadiusDegrees}}},
                  {"sky", vec(base.skyColor)},
                  {"ambient_intensity", base.ambientIntensity},
                  {"exposure", base.exposure}};
  doc["settings"] = {{"ao_range", plan.aoRange},
                     {"ao_estimator", "binary"},
                     {"reflection_roughness_threshold", plan.reflectionRoughness},
                     {"denoised_rows", "single frame: denoiser history reset before the captured frame"},
                     {"traced_rows_shadow_map_size", 1024}};
  doc["timing"] = {{"warmup_frames", plan.warmupFrames},
                   {"timed_frames", plan.timedFrames},
                   {"statistic", "median"},
                   {"source",
                    "GPU timestamps: SDK PassStats (traced passes), engine PassTimings (raster passes, frame)"},
                   {"frame_ms", "sum of the engine's passes (shadow map, pre-pass, SSAO, hook, lighting, tonemap); "
                                "without the probe capture and the shadow-visibility readback pass"}};
  if (raw) doc["raw_rate"] = {{"source", raw->source}, {"stress_grays_per_second", raw->graysPerSecond}};
  else if (!rawRateError.empty())
    doc["raw_rate"] = {{"source", o.rawRateJson}, {"error", rawRateError}};
  doc["effects"] = nlohmann::json::object();
  bool checksPassed = true;
  for (const EffectResult& r : results) {
    doc["effects"][r.effect] = toJson(r, raw);
    checksPassed = checksPassed && r.checkFailures.empty();
  }
  std::vector<std::string> motionFailures;
  if (motion) {
    doc["motion"] = motionResult;
    motionFailures = motionChecks(motionResult, uint64_t(width) * height);
    checksPassed = checksPassed && motionFailures.empty();
  }
  doc["checks_passed"] = checksPassed;
  doc["validation"] = {{"enabled", o.validation}, {"errors", driver.engine().validationErrorCount()}};
  doc["seconds"] = seconds;
  if (!o.out.empty()) {
    std::ofstream out(o.out);
    out << doc.dump(2) << "\n";
    if (!out) return fail("--out: cannot write '" + o.out + "'");
    std::printf("wrote %s\n", o.out.c_str());
  }
  std::printf("total %.1f s\n", seconds);

  int code = 0;
  for (const std::string& f : motionFailures) {
    std::fprintf(stderr, "raybridge-effects-bench: check failed: motion: %s\n", f.c_str());
    code = 4;
  }
  for (const EffectResult& r : results)
    for (const std::string& f : r.checkFailures) {
      std::fprintf(stderr, "raybridge-effects-bench: check failed: %s: %s\n", r.effect.c_str(), f.c_str());
      code = 4;
    }
  if (o.validation) {
    std::printf("validation errors: %u\n", driver.engine().validationErrorCount());
    if (driver.engine().validationErrorCount() > 0) return fail("the validation layer reported errors", 3);
  }
  return code;
}
