// tlas-motion: what TLAS refits cost in trace time as instances move apart, and what TlasBuildMode::Adaptive does
// about it. Small spheres and boxes fill a box; the moving ones each fly their own straight line at 5% of the
// spacing per frame and bounce off the walls, so neighbours at any build drift apart frame after frame (a crowd
// running every way, debris). Two cases: every instance moving (the worst case for a refit) and one in ten
// (a scene that is mostly still). Five AccelerationStructureServices build a TLAS over the same instance list
// every frame: `rebuild` (TlasBuildMode::Rebuild), `refit` (Adaptive with limits it never reaches: one build,
// then refits only; it reports the motion measure of its chain) and Adaptive with maxAreaGrowth 1.2, the default
// (kDefaultTlasMaxAreaGrowth) and 2. At frames 1, 2, 4, ... primary rays are traced over each TLAS at the bench
// resolution, in rounds that rotate the order of the variants (the first trace after a frame runs slower): trace
// time against the rebuilt TLAS, and the GPU build time per frame of each variant.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <random>

#include "gpu_timer.h"
#include "report.h"
#include "scenarios.h"
#include "scene_meshes.h"
#include "service_frames.h"
#include "trace_timing.h"

namespace rbbench {

namespace {

constexpr float kSpacing = 2.0f;                   // mean distance between instance origins (instances are ~1 wide)
constexpr float kStepPerFrame = 0.05f * kSpacing;  // distance each instance flies per frame

struct Flyer {
  float position[3];
  float velocity[3];
};

}  // namespace

namespace {

struct MotionVariant {
  std::string name;
  rb::TlasBuildOptions options;
  std::unique_ptr<rb::AccelerationStructureService> service;
  std::vector<rb::MeshHandle> handles;
  std::vector<rb::Instance> instances;
  rb::TlasInfo last;
  std::vector<double> gpuMs, hostMs, traceRatios;
  uint64_t builds = 0;
};

// One motion case: `moving` of every 10 instances fly, the others stay. Adds a row per checkpoint to `table`
// and a row per variant to `builds`.
void runMotionCase(BenchEnv& env, const std::vector<UploadedMesh>& meshes, uint32_t moving, Table& table,
                   Table& builds) {
  const BenchSizes& z = env.sizes();
  const uint32_t count = z.motionInstances;
  const std::string caseName = moving == 10 ? "all moving" : std::to_string(moving * 10) + "% moving";
  // A box four times as wide as it is tall holding `count` instances at kSpacing.
  const float width = std::cbrt(4.0f * float(count)) * kSpacing, height = width / 4.0f;
  std::vector<MotionVariant> variants(5);
  variants[0].name = "rebuild";
  variants[0].options.mode = rb::TlasBuildMode::Rebuild;
  variants[1].name = "refit";
  variants[1].options.mode = rb::TlasBuildMode::Adaptive;
  variants[1].options.maxAreaGrowth = 1e30f;
  variants[1].options.maxRefits = UINT32_MAX;
  const float growths[3] = {1.2f, 0.0f, 2.0f};
  for (int k = 0; k < 3; ++k) {
    MotionVariant& v = variants[2 + k];
    v.options.mode = rb::TlasBuildMode::Adaptive;
    v.options.maxAreaGrowth = growths[k];
    const float shown = growths[k] ? growths[k] : rb::kDefaultTlasMaxAreaGrowth;
    v.name = "adaptive " + std::to_string(shown).substr(0, 3) + (growths[k] ? "" : " (default)");
  }
  for (MotionVariant& v : variants) {
    v.service = check(rb::AccelerationStructureService::create(env.ctx()), "creating the AS service");
    for (size_t i = 0; i < meshes.size(); ++i)
      v.handles.push_back(registerOrThrow(*v.service, meshes[i].desc, "tlas-motion mesh " + std::to_string(i)));
    (void)buildQueued(env, *v.service);
    v.instances.resize(count);
    for (uint32_t i = 0; i < count; ++i) {
      v.instances[i].mesh = v.handles[i % v.handles.size()];
      v.instances[i].customIndex = i & 0xFFFFFFu;
    }
  }

  std::mt19937 rng(env.options().seed);
  std::uniform_real_distribution<float> unit(0.0f, 1.0f);
  std::vector<Flyer> flyers(count);
  for (uint32_t i = 0; i < count; ++i) {
    Flyer& f = flyers[i];
    f.position[0] = (unit(rng) - 0.5f) * width;
    f.position[1] = unit(rng) * height;
    f.position[2] = (unit(rng) - 0.5f) * width;
    // A uniform direction on the sphere; still instances keep a zero velocity.
    const float y = 2.0f * unit(rng) - 1.0f, phi = 6.2831853f * unit(rng), r = std::sqrt(1.0f - y * y);
    const float speed = i % 10 < moving ? kStepPerFrame : 0.0f;
    f.velocity[0] = r * std::cos(phi) * speed;
    f.velocity[1] = y * speed;
    f.velocity[2] = r * std::sin(phi) * speed;
  }
  const float lo[3] = {-0.5f * width, 0.0f, -0.5f * width}, hi[3] = {0.5f * width, height, 0.5f * width};
  auto place = [&] {  // the transforms; meshes and custom indices stay as set above
    for (MotionVariant& v : variants) {
      for (uint32_t i = 0; i < count; ++i) {
        setTransform(v.instances[i], translation(flyers[i].position[0], flyers[i].position[1], flyers[i].position[2]));
      }
    }
  };
  auto fly = [&] {
    for (Flyer& f : flyers) {
      for (int a = 0; a < 3; ++a) {
        f.position[a] += f.velocity[a];
        if (f.position[a] < lo[a] || f.position[a] > hi[a]) {
          f.velocity[a] = -f.velocity[a];
          f.position[a] = std::clamp(f.position[a], lo[a], hi[a]);
        }
      }
    }
  };

  // Seen from beyond one corner, slightly above: the whole box in view, instances hiding one another.
  rb::PrimaryRayCamera camera;
  camera.eye[0] = 0.9f * width;
  camera.eye[1] = 1.6f * height;
  camera.eye[2] = 0.9f * width;
  camera.target[1] = 0.3f * height;
  camera.verticalFovDegrees = 45.0f;
  auto pass = check(rb::PrimaryRayPass::create(env.ctx()), "creating the primary ray pass");

  const size_t n = variants.size();
  GpuTimer timer(env, uint32_t(n + 1));
  uint32_t nextCheckpoint = 1;
  for (uint32_t frame = 0; frame <= z.motionFrames; ++frame) {
    if (frame) fly();
    place();
    std::vector<uint32_t> marks(n + 1);
    std::vector<double> host(n);
    env.runFrame([&](VkCommandBuffer cmd) {
      timer.reset(cmd);
      marks[0] = timer.mark(cmd);
      for (size_t k = 0; k < n; ++k) {
        MotionVariant& v = variants[k];
        auto t0 = std::chrono::steady_clock::now();
        v.last = check(v.service->recordTlasBuild(cmd, v.instances, v.options), "recordTlasBuild");
        host[k] = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
        marks[k + 1] = timer.mark(cmd);
      }
    });
    timer.resolve();
    for (size_t k = 0; k < n; ++k) {
      MotionVariant& v = variants[k];
      if (v.last.instanceCount != count) throw BenchFailure("tlas-motion: a TLAS holds fewer instances than given");
      if (!v.last.updated) ++v.builds;
      if (frame == 0) continue;  // the first builds of the chains
      v.gpuMs.push_back(timer.ms(marks[k], marks[k + 1]));
      v.hostMs.push_back(host[k]);
    }
    if (frame > 0 && variants[0].last.updated) throw BenchFailure("tlas-motion: the rebuild variant refit");
    if (frame > 0 && !variants[1].last.updated) throw BenchFailure("tlas-motion: the refit variant rebuilt");
    if (frame != nextCheckpoint && frame != z.motionFrames) continue;
    nextCheckpoint *= 2;
    env.progress("tlas-motion: " + caseName + ", frame " + std::to_string(frame));
    // Rounds of one trace timing per variant, each round starting one variant later.
    std::vector<std::vector<double>> ms(n);
    std::vector<double> hits(n);
    // One round on a CPU device, whose timings have no such bias and whose traces take a tenth of a second.
    const size_t rounds = env.info().isCpu ? 1 : n;
    for (size_t round = 0; round < rounds; ++round) {
      for (size_t j = 0; j < n; ++j) {
        const size_t k = (round + j) % n;
        TraceTiming t = timeTraces(env, *pass, variants[k].last.tlas, camera, z.traceRepeats);
        ms[k].insert(ms[k].end(), t.ms.begin(), t.ms.end());
        hits[k] = t.hitFraction;
      }
    }
    // The TLASes hold the same instances: the same pixels hit, whatever their trees.
    for (size_t k = 1; k < n; ++k) {
      if (std::abs(hits[k] - hits[0]) > 1e-3)
        throw BenchFailure("tlas-motion: the " + variants[k].name + " TLAS hit " + std::to_string(hits[k]) +
                           " of the pixels, the rebuilt one " + std::to_string(hits[0]));
    }
    const double rebuildMs = median(ms[0]);
    nlohmann::json row = {{"case", caseName},
                          {"frame", frame},
                          {"spacingsFlown", frame * kStepPerFrame / kSpacing},
                          {"refitAreaGrowth", variants[1].last.areaGrowth},
                          {"rebuildTraceMs", rebuildMs},
                          {"hitFraction", hits[0]}};
    nlohmann::json perVariant = nlohmann::json::object();
    for (size_t k = 1; k < n; ++k) {
      const double traceMs = median(ms[k]);
      variants[k].traceRatios.push_back(ratio(traceMs, rebuildMs));
      perVariant[variants[k].name] = {{"traceMs", traceMs},
                                      {"overRebuild", ratio(traceMs, rebuildMs)},
                                      {"areaGrowth", variants[k].last.areaGrowth},
                                      {"builds", variants[k].builds}};
    }
    row["refitOverRebuild"] = perVariant["refit"]["overRebuild"];
    for (size_t k = 2; k < n; ++k)
      row["adaptive" + std::to_string(k - 1) + "OverRebuild"] = perVariant[variants[k].name]["overRebuild"];
    row["variants"] = perVariant;
    table.add(row);
  }
  for (MotionVariant& v : variants) {
    double sum = 0.0, worst = 0.0, ratioSum = 0.0;
    for (double x : v.gpuMs) {
      sum += x;
      worst = std::max(worst, x);
    }
    for (double r : v.traceRatios) ratioSum += r;
    builds.add({{"case", caseName},
                {"variant", v.name},
                {"builds", v.builds},
                {"gpuMeanMs", v.gpuMs.empty() ? 0.0 : sum / double(v.gpuMs.size())},
                {"gpuMaxMs", worst},
                {"hostMedianMs", median(v.hostMs)},
                {"meanTraceOverRebuild", v.traceRatios.empty() ? 1.0 : ratioSum / double(v.traceRatios.size())}});
  }
  pass.reset();
  env.settle();
  variants.clear();
}

}  // namespace

nlohmann::json runTlasMotionScenario(BenchEnv& env) {
  const BenchSizes& z = env.sizes();
  std::vector<rbsamples::CpuMesh> cpu = {rbsamples::makeSphere(0.5f, 16, 10)};
  const float boxMin[3] = {-0.5f, -0.5f, -0.5f}, boxMax[3] = {0.5f, 0.5f, 0.5f};
  cpu.push_back(rbsamples::makeBox(boxMin, boxMax, 2));
  std::vector<UploadedMesh> meshes;
  for (const rbsamples::CpuMesh& m : cpu) meshes.push_back(env.upload(m, "tlas-motion mesh"));

  Table table("tlas-motion: " + humanCount(z.motionInstances) + " instances, the moving ones at " +
                  std::to_string(kStepPerFrame / kSpacing).substr(0, 4) + " spacings per frame; " +
                  std::to_string(z.width) + "x" + std::to_string(z.height) + " primary rays, median of " +
                  std::to_string(z.traceRepeats) +
                  " traces x 5 rounds (1 on a CPU); trace time over the rebuilt TLAS's",
              {{"case", "case"},
               {"frame", "frame"},
               {"spacings", "spacingsFlown", 1},
               {"refit growth", "refitAreaGrowth", 2},
               {"rebuild ms", "rebuildTraceMs", 3},
               {"refit", "refitOverRebuild", 2},
               {"adaptive 1.2", "adaptive1OverRebuild", 2},
               {"adaptive 1.5", "adaptive2OverRebuild", 2},
               {"adaptive 2.0", "adaptive3OverRebuild", 2}});
  Table builds("tlas-motion: TLAS per frame over " + std::to_string(z.motionFrames) + " frames",
               {{"case", "case"},
                {"variant", "variant"},
                {"builds", "builds"},
                {"GPU ms mean", "gpuMeanMs", 3},
                {"GPU ms max", "gpuMaxMs", 3},
                {"host ms median", "hostMedianMs", 3},
                {"trace / rebuild, mean", "meanTraceOverRebuild", 2}});
  for (uint32_t moving : {10u, 1u}) runMotionCase(env, meshes, moving, table, builds);
  table.print();
  builds.print();
  nlohmann::json summary = nlohmann::json::object();
  for (const nlohmann::json& r : builds.rows()) {
    const std::string key = r["case"].get<std::string>() + ", " + r["variant"].get<std::string>();
    summary[key + ": GPU ms mean"] = r["gpuMeanMs"];
    summary[key + ": trace / rebuild, mean"] = r["meanTraceOverRebuild"];
  }
  printSummary(summary);
  env.settle();
  for (UploadedMesh& m : meshes) env.destroy(m);
  return {{"instances", z.motionInstances}, {"frames", z.motionFrames}, {"width", z.width},  {"height", z.height},
          {"rows", table.rows()},           {"builds", builds.rows()},  {"summary", summary}};
}

}  // namespace rbbench
