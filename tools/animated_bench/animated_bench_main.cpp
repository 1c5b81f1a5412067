// raybridge-animated-bench: K skinned characters walking (in place) on the demo scene, hard shadows and AO at
// 2560x1440, in each way of keeping their BLASes up to date: refit in the frame (adaptive policy), refit only,
// rebuild every frame, async on the engine's compute queue (same frame), async one frame late, and the same scene
// with the characters frozen. Per frame: graphics-queue GPU time (the engine's timestamps, which include the
// SDK's hook), the frame interval on the CPU (which also shows queue stalls), async-queue GPU time, BLAS
// triangles refit and rebuilt, shadow-pass time. Writes JSON and prints a table.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "animated_scene.h"
#include "cli_support.h"
#include "raybridge_sample_engine_adapter.h"

namespace se = sample_engine;
using nlohmann::json;

namespace {

struct Options {
  std::vector<uint32_t> characters = {1, 10, 50, 200};
  uint32_t frames = 300, warmup = 30;
  uint32_t width = 2560, height = 1440;
  std::string scenes = std::string(RAYBRIDGE_SOURCE_DIR) + "/../shared/scenes";
  std::string out = "animated_bench.json";
  std::string modes;  // comma-separated subset of the mode names; empty = all
  std::string device;
  bool validation = false;
  bool quick = false;
};

struct Mode {
  const char* name;
  rb::DynamicBuildMode dynamicMode;
  rb::RefitPolicyKind policy;
  bool frozen;
  const char* what;
};
const Mode kModes[] = {
    {"sync-refit", rb::DynamicBuildMode::InFrame, rb::RefitPolicyKind::Adaptive, false,
     "in the frame: refit, rebuilt by the policy"},
    {"sync-refit-only", rb::DynamicBuildMode::InFrame, rb::RefitPolicyKind::AlwaysRefit, false,
     "in the frame: refit only, never rebuilt"},
    {"sync-rebuild", rb::DynamicBuildMode::InFrame, rb::RefitPolicyKind::AlwaysRebuild, false,
     "in the frame: rebuilt every frame"},
    {"async", rb::DynamicBuildMode::AsyncSameFrame, rb::RefitPolicyKind::Adaptive, false,
     "async queue, this frame's TLAS waits for it (policy)"},
    {"async-late", rb::DynamicBuildMode::AsyncOneFrameLate, rb::RefitPolicyKind::Adaptive, false,
     "async queue, TLAS uses the previous frame's BLAS (policy)"},
    {"frozen", rb::DynamicBuildMode::AsyncOneFrameLate, rb::RefitPolicyKind::Adaptive, true,
     "characters frozen: no BLAS work (baseline)"},
};

std::vector<std::string> modeNames() {
  std::vector<std::string> names;
  for (const Mode& m : kModes) names.push_back(m.name);
  return names;
}

void addOptions(CLI::App& app, Options& o) {
  rbCli::prepare(app);
  app.description(
      "Skinned characters walking on the demo scene with hard shadows and AO, in each way of keeping their BLASes\n"
      "up to date; writes JSON and prints a table.");
  app.add_option_function<std::string>(
         "--characters", [&o](const std::string& v) { rbCli::parseWholeNumberList(v, 1, 9999, o.characters); },
         "character counts, one run each (default 1,10,50,200)")
      ->type_name("N,N,...")
      ->check(CLI::Validator(
          [](std::string& v) {
            std::vector<uint32_t> counts;
            return rbCli::parseWholeNumberList(v, 1, 9999, counts);
          },
          ""));
  app.add_option("--frames", o.frames, "measured frames per run (default 300)")
      ->type_name("N")
      ->check(rbCli::wholeNumber(2, 100000));
  app.add_option("--warmup", o.warmup, "frames before measuring (default 30)")
      ->type_name("N")
      ->check(rbCli::wholeNumber(1, 10000));
  app.add_option("--width", o.width, "image width (default 2560)")->type_name("W")->check(rbCli::wholeNumber(16, 8192));
  app.add_option("--height", o.height, "image height (default 1440)")
      ->type_name("H")
      ->check(rbCli::wholeNumber(16, 8192));
  std::string modes;
  for (const Mode& m : kModes) modes += std::string("\n  ") + m.name + ": " + m.what;
  app.add_option("--modes", o.modes, "comma-separated subset of the modes (default: all):" + modes)
      ->type_name("LIST")
      ->check(CLI::Validator(
          [](std::string& v) {
            uint32_t set = 0;
            return rbCli::parseNameSet(v, modeNames(), "a mode", set);
          },
          ""));
  app.add_option("--scenes", o.scenes, "folder of the glTF models (default ../shared/scenes)")->type_name("DIR");
  app.add_option("--out", o.out, "JSON report (default animated_bench.json)")->type_name("FILE.json");
  app.add_option("--device", o.device, "pick the Vulkan device whose name contains SUBSTR")->type_name("SUBSTR");
  app.add_flag("--validation", o.validation, "enable VK_LAYER_KHRONOS_validation (also RAYBRIDGE_VALIDATION=1)");
  app.add_flag("--quick", o.quick, "1 and 2 characters, 12 frames at 192x108 (a smoke run for CI, with\n--validation)");
}

std::string usage() {
  Options unused;
  CLI::App app{"", "raybridge-animated-bench"};
  addOptions(app, unused);
  return app.help();
}

// Parses argv; returns "" or an error naming the option and the value. --help prints the help and exits 0.
std::string parse(int argc, char** argv, Options& o) {
  CLI::App app{"", "raybridge-animated-bench"};
  addOptions(app, o);
  bool help = false;
  if (std::string e = rbCli::parse(app, argc, argv, help); !e.empty()) return e;
  if (help) {
    std::printf("%s", app.help().c_str());
    std::exit(0);
  }
  if (o.quick) {
    o.characters = {1, 2};
    o.frames = 12;
    o.warmup = 3;
    o.width = 192;
    o.height = 108;
  }
  return {};
}

bool wanted(const Options& o, const Mode& m) {
  return o.modes.empty() || ("," + o.modes + ",").find(std::string(",") + m.name + ",") != std::string::npos;
}

double percentile(std::vector<double> v, double p) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  const double at = p * double(v.size() - 1);
  const size_t lo = size_t(at), hi = std::min(lo + 1, v.size() - 1);
  return v[lo] + (v[hi] - v[lo]) * (at - double(lo));
}
double mean(const std::vector<double>& v) {
  double s = 0.0;
  for (double x : v) s += x;
  return v.empty() ? 0.0 : s / double(v.size());
}

struct Series {
  std::vector<double> graphicsMs, intervalMs, hookMs, deformMs, asyncMs, shadowMs, refitTriangles, rebuildTriangles,
      staleBlas;
  double blasGpuMs = 0.0;  // resolved BLAS build/refit batches (both queues) recorded in the timed frames
};

// One mode at one character count: a fresh adapter (its own service, policy and queue use) on the loaded scene.
se::Result<json> runMode(se::Engine& engine, const rbAnimated::AnimatedScene& scene, const Mode& mode,
                         const Options& o) {
  using R = se::Result<json>;
  rbAdapter::AdapterConfig ac;
  ac.preset = rb::Preset::Low;  // hard shadows, AO 4
  ac.accelerationStructures.dynamicMode = mode.dynamicMode;
  ac.accelerationStructures.refitPolicy.kind = mode.policy;
  auto created = rbAdapter::Adapter::create(engine, ac);
  if (!created) return R::failure("adapter: " + created.error);
  rbAdapter::Adapter& adapter = *created.value;
  engine.setPrepassHook(adapter.prepassHook());

  se::FrameParams params;
  params.camera = engine.scene().camera ? *engine.scene().camera : se::defaultCameraFor(engine.sceneBounds());
  if (engine.scene().sun) params.sun = *engine.scene().sun;
  params.animations = scene.playbacks;
  const double dt = 1.0 / 60.0;

  Series s;
  uint64_t lastTimingsFrame = 0;
  uint64_t timedFromFrame = UINT64_MAX;  // Context::frameIndex() of the first timed frame
  uint64_t batchesThrough = 0;           // batches of frames up to this one are counted
  auto countBatches = [&](const rb::AsStats& as) {
    uint64_t newest = batchesThrough;
    for (const rb::BuildBatchTiming& b : as.batches) {
      if (b.frame <= batchesThrough) continue;
      if (b.frame >= timedFromFrame) s.blasGpuMs += b.gpuMs;
      newest = std::max(newest, b.frame);
    }
    batchesThrough = newest;
  };
  auto t0 = std::chrono::steady_clock::now();
  const uint32_t total = o.warmup + o.frames;
  for (uint32_t f = 0; f < total; ++f) {
    // Frozen: the pose of the first timed frame forever, and the SDK is told nothing moved.
    params.time = mode.frozen ? double(o.warmup) * dt : double(f) * dt;
    adapter.settings().updateDeformedMeshes = !mode.frozen || f == 0;
    if (se::Status st = engine.renderFrame(params); !st) return R::failure(st.error);
    if (!adapter.lastError().empty()) return R::failure("Raybridge: " + adapter.lastError());
    const auto t1 = std::chrono::steady_clock::now();
    const double interval = std::chrono::duration<double, std::milli>(t1 - t0).count();
    t0 = t1;
    const rb::AsStats as = adapter.accelerationStructures().stats();
    countBatches(as);
    if (f + 1 == o.warmup) timedFromFrame = adapter.context().frameIndex() + 1;
    if (f < o.warmup) continue;
    // renderFrame waited for the frame slot's fence, so the timings of an earlier frame are in.
    const se::PassTimings t = engine.lastTimings();
    s.intervalMs.push_back(interval);
    if (t.valid && t.frameNumber != lastTimingsFrame) {
      lastTimingsFrame = t.frameNumber;
      s.graphicsMs.push_back(t.deformMs + t.shadowMs + t.prepassMs + t.hookMs + t.lightingMs + t.tonemapMs);
      s.hookMs.push_back(t.hookMs);
      s.deformMs.push_back(t.deformMs);
    }
    // The latest resolved async submission, in frames that submitted one (a frozen frame submits nothing).
    const bool submitted = as.async && as.lastFrameRefitTriangles + as.lastFrameRebuildTriangles > 0;
    s.asyncMs.push_back(submitted ? as.lastAsyncGpuMs : 0.0);
    s.shadowMs.push_back(adapter.effects().stats().shadow.gpuMs);
    s.refitTriangles.push_back(double(as.lastFrameRefitTriangles));
    s.rebuildTriangles.push_back(double(as.lastFrameRebuildTriangles));
    s.staleBlas.push_back(double(as.staleBlas));
  }
  if (se::Status st = engine.waitIdle(); !st) return R::failure(st.error);
  adapter.context().releaseAfterIdle();
  const rb::AsStats as = adapter.accelerationStructures().stats();
  countBatches(as);
  const rb::MemoryStats mem = adapter.context().memoryStats();
  engine.setPrepassHook({});

  json r;
  r["mode"] = mode.name;
  r["what"] = mode.what;
  r["async"] = as.async;
  r["async_queue_family"] = as.async ? json(as.asyncQueueFamily) : json(nullptr);
  r["async_fallback_reason"] = as.asyncFallbackReason;
  r["graphics_ms"] = {{"p50", percentile(s.graphicsMs, 0.5)},
                      {"p99", percentile(s.graphicsMs, 0.99)},
                      {"mean", mean(s.graphicsMs)}};
  r["frame_interval_ms"] = {{"p50", percentile(s.intervalMs, 0.5)},
                            {"p99", percentile(s.intervalMs, 0.99)},
                            {"mean", mean(s.intervalMs)}};
  r["hook_ms_mean"] = mean(s.hookMs);
  r["deform_ms_mean"] = mean(s.deformMs);
  r["async_ms_mean"] = mean(s.asyncMs);
  r["blas_gpu_ms_per_frame"] = s.blasGpuMs / double(o.frames);
  r["shadow_ms_mean"] = mean(s.shadowMs);
  r["refit_triangles_per_frame"] = mean(s.refitTriangles);
  r["rebuild_triangles_per_frame"] = mean(s.rebuildTriangles);
  r["stale_blas_mean"] = mean(s.staleBlas);
  r["refits"] = as.refits;
  r["rebuilds"] = as.rebuilds;
  r["memory_bytes"] = mem.total();
  r["dynamic_blas_bytes"] = as.dynamicBlasBytes;
  r["frames"] = {
      {"graphics_ms", s.graphicsMs}, {"interval_ms", s.intervalMs},         {"async_ms", s.asyncMs},
      {"shadow_ms", s.shadowMs},     {"refit_triangles", s.refitTriangles}, {"rebuild_triangles", s.rebuildTriangles}};
  return R::success(std::move(r));
}

}  // namespace

int main(int argc, char** argv) {
  Options o;
  if (std::string e = parse(argc, argv, o); !e.empty()) {
    std::fprintf(stderr, "raybridge-animated-bench: error: %s\n%s", e.c_str(), usage().c_str());
    return 2;
  }
  if (const char* v = std::getenv("RAYBRIDGE_VALIDATION"); v && std::string(v) == "1") o.validation = true;
  // The models come from the shared folder; without them there is nothing to animate.
  if (auto probe = rbAnimated::makeAnimatedScene(o.scenes, 1); !probe) {
    std::printf("raybridge-animated-bench: skipped: %s; pass --scenes with the folder of the shared glTF models\n",
                probe.error.c_str());
    return 0;
  }

  rb::RequiredFeatures features;
  se::EngineConfig config;
  config.enableValidation = o.validation;
  config.deviceNameFilter = o.device;
  config.applicationName = "raybridge-animated-bench";
  rbAdapter::configureEngine(config, features);
  auto created = se::Engine::create(config);
  if (!created) return std::fprintf(stderr, "engine: %s\n", created.error.c_str()), 1;
  se::Engine& engine = *created.value;
  if (se::Status s = engine.setRenderSize(o.width, o.height); !s)
    return std::fprintf(stderr, "%s\n", s.error.c_str()), 1;

  json report;
  report["device"] = engine.deviceInfo().name;
  report["async_compute_queue_family"] = engine.asyncComputeQueue() ? json(engine.asyncComputeQueueFamily())
                                                                    : json(nullptr);
  report["width"] = o.width;
  report["height"] = o.height;
  report["frames"] = o.frames;
  report["warmup"] = o.warmup;
  report["effects"] = "hard shadows (1 ray) + AO (4 rays, denoised)";
  report["runs"] = json::array();
  std::printf("device %s, %ux%u, %u frames per run (after %u warm-up), async compute family %s\n",
              engine.deviceInfo().name.c_str(), o.width, o.height, o.frames, o.warmup,
              engine.asyncComputeQueue() ? std::to_string(engine.asyncComputeQueueFamily()).c_str() : "none");
  std::printf(
      "| characters | mode | graphics p50 ms | p99 ms | interval p50 ms | p99 ms | async ms | BLAS ms | shadow ms | "
      "refit tris/frame | rebuild tris/frame | stale | memory MiB "
      "|\n|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
  for (uint32_t k : o.characters) {
    auto scene = rbAnimated::makeAnimatedScene(o.scenes, k);
    if (!scene) return std::fprintf(stderr, "%s\n", scene.error.c_str()), 1;
    if (se::Status s = engine.loadScene(scene.value.scene); !s) return std::fprintf(stderr, "%s\n", s.error.c_str()), 1;
    for (const Mode& m : kModes) {
      if (!wanted(o, m)) continue;
      auto r = runMode(engine, scene.value, m, o);
      if (!r) return std::fprintf(stderr, "%u characters, %s: %s\n", k, m.name, r.error.c_str()), 1;
      json run = r.value;
      run["characters"] = k;
      run["character_triangles"] = scene.value.characterTriangles;
      std::printf("| %u | %s | %.3f | %.3f | %.3f | %.3f | %.3f | %.3f | %.3f | %.0f | %.0f | %.1f | %.1f |\n", k,
                  m.name, run["graphics_ms"]["p50"].get<double>(), run["graphics_ms"]["p99"].get<double>(),
                  run["frame_interval_ms"]["p50"].get<double>(), run["frame_interval_ms"]["p99"].get<double>(),
                  run["async_ms_mean"].get<double>(), run["blas_gpu_ms_per_frame"].get<double>(),
                  run["shadow_ms_mean"].get<double>(), run["refit_triangles_per_frame"].get<double>(),
                  run["rebuild_triangles_per_frame"].get<double>(), run["stale_blas_mean"].get<double>(),
                  run["memory_bytes"].get<double>() / 1048576.0);
      std::fflush(stdout);
      report["runs"].push_back(std::move(run));
    }
  }
  report["validation"] = {{"enabled", o.validation}, {"errors", engine.validationErrorCount()}};
  std::ofstream(o.out) << report.dump(1) << "\n";
  std::printf("wrote %s\n", o.out.c_str());
  if (o.validation && engine.validationErrorCount() > 0) {
    std::fprintf(stderr, "the validation layer reported %u errors\n", engine.validationErrorCount());
    return 3;
  }
  return 0;
}
