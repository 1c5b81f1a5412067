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

const char* kUsage =
    "usage: raybridge-animated-bench [--characters 1,10,50,200] [--frames 300] [--warmup 30] [--width 2560]\n"
    "         [--height 1440] [--modes sync-refit,sync-refit-only,sync-rebuild,async,async-late,frozen]\n"
    "         [--scenes DIR] [--out FILE.json] [--device SUBSTR] [--validation] [--quick]\n"
    "  --quick: 1 and 2 characters, 12 frames at 192x108 (a smoke run for CI, with --validation)\n";

bool parseList(const std::string& text, std::vector<uint32_t>& out) {
  out.clear();
  size_t start = 0;
  while (start <= text.size()) {
    const size_t comma = text.find(',', start);
    const std::string item = text.substr(start, comma == std::string::npos ? std::string::npos : comma - start);
    if (item.empty() || item.find_first_not_of("0123456789") != std::string::npos || item.size() > 4) return false;
    out.push_back(uint32_t(std::stoul(item)));
    if (out.back() == 0) return false;
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
  return !out.empty();
}

std::string parse(int argc, char** argv, Options& o) {
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto value = [&]() -> const char* { return i + 1 < argc ? argv[++i] : nullptr; };
    auto number = [&](uint32_t& out, uint32_t min, uint32_t max) -> std::string {
      const char* v = value();
      if (!v) return a + " needs a value";
      std::vector<uint32_t> one;
      if (!parseList(v, one) || one.size() != 1 || one[0] < min || one[0] > max)
        return a + ": '" + v + "' is not a whole number in " + std::to_string(min) + ".." + std::to_string(max);
      out = one[0];
      return {};
    };
    std::string e;
    if (a == "--quick") {
      o.quick = true;
    } else if (a == "--validation") {
      o.validation = true;
    } else if (a == "--characters") {
      const char* v = value();
      if (!v || !parseList(v, o.characters)) return "--characters: expected counts like 1,10,50,200";
    } else if (a == "--frames") {
      e = number(o.frames, 2, 100000);
    } else if (a == "--warmup") {
      e = number(o.warmup, 1, 10000);
    } else if (a == "--width") {
      e = number(o.width, 16, 8192);
    } else if (a == "--height") {
      e = number(o.height, 16, 8192);
    } else if (a == "--scenes" || a == "--out" || a == "--modes" || a == "--device") {
      const char* v = value();
      if (!v) return a + " needs a value";
      (a == "--scenes" ? o.scenes : a == "--out" ? o.out : a == "--modes" ? o.modes : o.device) = v;
    } else if (a == "--help" || a == "-h") {
      std::printf("%s", kUsage);
      std::exit(0);
    } else {
      return "unknown option '" + a + "'";
    }
    if (!e.empty()) return e;
  }
  if (o.quick) {
    o.characters = {1, 2};
    o.frames = 12;
    o.warmup = 3;
    o.width = 192;
    o.height = 108;
  }
  if (!o.modes.empty()) {
    std::string rest = o.modes + ",";
    for (size_t p; (p = rest.find(',')) != std::string::npos; rest.erase(0, p + 1)) {
      const std::string m = rest.substr(0, p);
      if (std::none_of(std::begin(kModes), std::end(kModes), [&](const Mode& k) { return m == k.name; }))
        return "--modes: '" + m + "' is not one of sync-refit, sync-refit-only, sync-rebuild, async, async-late, frozen";
    }
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
  ac.effects = rbAdapter::kEffectShadows | rbAdapter::kEffectAo;
  ac.accelerationStructures.dynamicMode = mode.dynamicMode;
  ac.accelerationStructures.refitPolicy.kind = mode.policy;
  auto created = rbAdapter::Adapter::create(engine, ac);
  if (!created) return R::failure("adapter: " + created.error);
  rbAdapter::Adapter& adapter = *created.value;
  if (se::Status s = adapter.applyPreset(rbAdapter::Preset::Low); !s) return R::failure(s.error);  // hard shadows, AO 4
  engine.setPrepassHook(adapter.prepassHook());

  se::FrameParams params;
  params.camera = engine.scene().camera ? *engine.scene().camera : se::defaultCameraFor(engine.sceneBounds());
  if (engine.scene().sun) params.sun = *engine.scene().sun;
  adapter.settings().lightingFrom(params);
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
    s.shadowMs.push_back(adapter.stats().shadow.gpuMs);
    s.refitTriangles.push_back(double(as.lastFrameRefitTriangles));
    s.rebuildTriangles.push_back(double(as.lastFrameRebuildTriangles));
    s.staleBlas.push_back(double(as.staleBlas));
  }
  if (se::Status st = engine.waitIdle(); !st) return R::failure(st.error);
  adapter.releaseAfterIdle();
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
  r["graphics_ms"] = {{"p50", percentile(s.graphicsMs, 0.5)}, {"p99", percentile(s.graphicsMs, 0.99)},
                      {"mean", mean(s.graphicsMs)}};
  r["frame_interval_ms"] = {{"p50", percentile(s.intervalMs, 0.5)}, {"p99", percentile(s.intervalMs, 0.99)},
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
  r["frames"] = {{"graphics_ms", s.graphicsMs}, {"interval_ms", s.intervalMs}, {"async_ms", s.asyncMs},
                 {"shadow_ms", s.shadowMs},     {"refit_triangles", s.refitTriangles},
                 {"rebuild_triangles", s.rebuildTriangles}};
  return R::success(std::move(r));
}

}  // namespace

int main(int argc, char** argv) {
  Options o;
  if (std::string e = parse(argc, argv, o); !e.empty()) {
    std::fprintf(stderr, "raybridge-animated-bench: error: %s\n%s", e.c_str(), kUsage);
    return 2;
  }
  if (const char* v = std::getenv("RAYBRIDGE_VALIDATION"); v && std::string(v) == "1") o.validation = true;
  // The models come from the shared folder; without them there is nothing to animate.
  if (auto probe = rbAnimated::makeAnimatedScene(o.scenes, 1); !probe) {
    std::printf("raybridge-animated-bench: skipped: %s\n", probe.error.c_str());
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
  if (se::Status s = engine.setRenderSize(o.width, o.height); !s) return std::fprintf(stderr, "%s\n", s.error.c_str()), 1;

  json report;
  report["device"] = engine.deviceInfo().name;
  report["async_compute_queue_family"] =
      engine.asyncComputeQueue() ? json(engine.asyncComputeQueueFamily()) : json(nullptr);
  report["width"] = o.width;
  report["height"] = o.height;
  report["frames"] = o.frames;
  report["warmup"] = o.warmup;
  report["effects"] = "hard shadows (1 ray) + AO (4 rays, denoised)";
  report["runs"] = json::array();
  std::printf("device %s, %ux%u, %u frames per run (after %u warm-up), async compute family %s\n",
              engine.deviceInfo().name.c_str(), o.width, o.height, o.frames, o.warmup,
              engine.asyncComputeQueue() ? std::to_string(engine.asyncComputeQueueFamily()).c_str() : "none");
  std::printf("| characters | mode | graphics p50 ms | p99 ms | interval p50 ms | p99 ms | async ms | BLAS ms | shadow ms | "
              "refit tris/frame | rebuild tris/frame | stale | memory MiB |\n|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
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
                  run["shadow_ms_mean"].get<double>(),
                  run["refit_triangles_per_frame"].get<double>(), run["rebuild_triangles_per_frame"].get<double>(),
                  run["stale_blas_mean"].get<double>(), run["memory_bytes"].get<double>() / 1048576.0);
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
