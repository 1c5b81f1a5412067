// trace: raw primary-ray rate (one ray per pixel, closest hit) on a finely tessellated scene, a bumpy ground
// with spheres standing on it, seen from above, and for reference rays that miss everything. A third view
// rebuilds the independent probe's scene (../shared/tools/rt-probe: a ground in 64x64 tiles and 32x32 UV spheres,
// 991,232 triangles in one BLAS) and traces it from the probe's primary camera, so that the pass's rate can be
// set against the probe's primary rate on the same rays.
#include <algorithm>
#include <memory>

#include "report.h"
#include "scenarios.h"
#include "scene_meshes.h"
#include "service_frames.h"
#include "trace_timing.h"

namespace rbbench {

namespace {

// The probe's makeScene(K, seg, T) (probe.cpp): spheres of radius 0.4 on a grid of spacing 1, seg slices and
// seg / 2 stacks (seg * (seg - 2) triangles each), standing on a ground of half-size max(20 K, 50) in T x T tiles.
constexpr uint32_t kProbeSpheresPerSide = 32;
constexpr uint32_t kProbeSphereSegments = 32;
constexpr uint32_t kProbeGroundTiles = 64;

rbsamples::CpuMesh probeScene() {
  const float extent = float(kProbeSpheresPerSide);
  const float groundHalf = std::max(20.0f * extent, 50.0f);
  rbsamples::CpuMesh scene = rbsamples::makeGrid(2.0f * groundHalf, kProbeGroundTiles);
  const float radius = 0.4f;
  const rbsamples::CpuMesh sphere = rbsamples::makeSphere(radius, kProbeSphereSegments, kProbeSphereSegments / 2);
  const float centre = float(kProbeSpheresPerSide - 1) * 0.5f;
  for (uint32_t i = 0; i < kProbeSpheresPerSide; ++i) {
    for (uint32_t j = 0; j < kProbeSpheresPerSide; ++j) {
      rbsamples::appendTranslated(scene, sphere, float(i) - centre, radius, float(j) - centre);
    }
  }
  return scene;
}

// The probe's primary camera: low pitch towards the centre, 60 degrees vertically, the horizon in view (the top of
// the image misses).
rb::PrimaryRayCamera probeCamera() {
  const float extent = float(kProbeSpheresPerSide);
  rb::PrimaryRayCamera camera;
  camera.eye[1] = 0.3f * extent + 0.5f;
  camera.eye[2] = 1.2f * extent + 1.0f;
  camera.target[2] = 0.0f;
  camera.verticalFovDegrees = 60.0f;
  return camera;
}

struct TracedScene {
  std::unique_ptr<rb::AccelerationStructureService> service;
  std::vector<UploadedMesh> meshes;
  rb::TlasInfo tlas;
  uint64_t triangles = 0;
};

// Registers the meshes, builds and compacts their BLASes, then one TLAS over `instances` (whose mesh fields index
// `cpu` until then).
TracedScene buildScene(BenchEnv& env, const std::vector<rbsamples::CpuMesh>& cpu, std::vector<rb::Instance> instances,
                       const std::vector<uint32_t>& meshOfInstance) {
  TracedScene s;
  s.service = check(rb::AccelerationStructureService::create(env.ctx()), "creating the AS service");
  std::vector<rb::MeshHandle> handles;
  for (size_t i = 0; i < cpu.size(); ++i) {
    s.meshes.push_back(env.upload(cpu[i], "trace mesh"));
    handles.push_back(registerOrThrow(*s.service, s.meshes.back().desc, "trace mesh " + std::to_string(i)));
  }
  for (size_t i = 0; i < instances.size(); ++i) {
    instances[i].mesh = handles[meshOfInstance[i]];
    s.triangles += cpu[meshOfInstance[i]].triangleCount();
  }
  (void)buildQueued(env, *s.service);
  env.runFrame([&](VkCommandBuffer cmd) { (void)check(s.service->recordPendingWork(cmd), "compaction frame"); });
  env.settle();
  env.runFrame(
      [&](VkCommandBuffer cmd) { s.tlas = check(s.service->recordTlasBuild(cmd, instances, kStaticTlas), "TLAS"); });
  env.settle();
  return s;
}

void destroyScene(BenchEnv& env, TracedScene& s) {
  s.service.reset();
  for (UploadedMesh& m : s.meshes) env.destroy(m);
  s.meshes.clear();
}

}  // namespace

nlohmann::json runTraceScenario(BenchEnv& env) {
  const BenchSizes& z = env.sizes();
  const float size = 100.0f;
  std::vector<rbsamples::CpuMesh> cpu = {groundWithAbout(z.traceTriangles * 3 / 4, size),
                                         rbsamples::makeSphereWithAbout(z.traceTriangles / 4 / 9, 6.0f)};
  std::vector<rb::Instance> instances(1);
  std::vector<uint32_t> meshOfInstance = {0};
  for (int i = 0; i < 9; ++i) {
    rb::Instance inst;
    inst.customIndex = uint32_t(i + 1);
    setTransform(inst, translation(-30.0f + 30.0f * float(i % 3), 6.0f, -30.0f + 30.0f * float(i / 3)));
    instances.push_back(inst);
    meshOfInstance.push_back(1);
  }
  TracedScene ground = buildScene(env, cpu, instances, meshOfInstance);
  cpu.clear();

  auto pass = check(rb::PrimaryRayPass::create(env.ctx()), "creating the primary ray pass");
  Table table("trace: primary rays, " + std::to_string(z.width) + "x" + std::to_string(z.height) + ", median of " +
                  std::to_string(z.traceRepeats) + " traces",
              {{"view", "view"},
               {"triangles", "triangles"},
               {"rays", "rays"},
               {"median ms", "medianMs", 3},
               {"min ms", "minMs", 3},
               {"Mrays/s", "mraysPerSecond", 2},
               {"GRays/s", "graysPerSecond", 4},
               {"hits", "hitFraction", 3}});
  auto addRow = [&](const char* name, const TracedScene& scene, const rb::PrimaryRayCamera& camera) {
    env.progress(std::string("trace: ") + name);
    TraceTiming t = timeTraces(env, *pass, scene.tlas.tlas, camera, z.traceRepeats);
    table.add({{"view", name},
               {"triangles", scene.triangles},
               {"rays", uint64_t(z.width) * z.height},
               {"medianMs", t.medianMs},
               {"minMs", t.minMs},
               {"allMs", t.ms},
               {"mraysPerSecond", t.raysPerSecond * 1e-6},
               {"graysPerSecond", t.raysPerSecond * 1e-9},
               {"hitFraction", t.hitFraction}});
  };
  rb::PrimaryRayCamera sky;
  sky.eye[1] = 20.0f;
  sky.target[1] = 100.0f;
  sky.target[2] = -10.0f;
  addRow("ground + spheres", ground, cameraOverGround(size));
  addRow("sky (all miss)", ground, sky);
  destroyScene(env, ground);

  // The probe's scene at every size (about a million triangles whatever --quick says: its BLAS builds in about a
  // second on lavapipe), so that the view the docs compare with the probe is the one CI runs.
  TracedScene probe = buildScene(env, {probeScene()}, {rb::Instance{}}, {0});
  addRow("probe scene, probe camera", probe, probeCamera());
  destroyScene(env, probe);
  table.print();
  pass.reset();
  const auto& rows = table.rows();
  nlohmann::json summary = {{"missOverHitRate", ratio(rows[1]["mraysPerSecond"], rows[0]["mraysPerSecond"])}};
  printSummary(summary);
  return {{"width", z.width}, {"height", z.height}, {"rows", rows}, {"summary", summary}};
}

}  // namespace rbbench
