// trace: raw primary-ray rate (one ray per pixel, closest hit) on a finely tessellated scene, a bumpy ground
// with spheres standing on it, seen from above, and for reference rays that miss everything.
#include "report.h"
#include "scenarios.h"
#include "scene_meshes.h"
#include "service_frames.h"
#include "trace_timing.h"

namespace rbbench {

nlohmann::json runTraceScenario(BenchEnv& env) {
  const BenchSizes& z = env.sizes();
  const float size = 100.0f;
  std::vector<rbsamples::CpuMesh> cpu = {groundWithAbout(z.traceTriangles * 3 / 4, size),
                                         rbsamples::makeSphereWithAbout(z.traceTriangles / 4 / 9, 6.0f)};
  auto service = check(rb::AccelerationStructureService::create(env.ctx()), "creating the AS service");
  std::vector<UploadedMesh> meshes;
  std::vector<rb::MeshHandle> handles;
  for (size_t i = 0; i < cpu.size(); ++i) {
    meshes.push_back(env.upload(cpu[i], "trace mesh"));
    handles.push_back(registerOrThrow(*service, meshes.back().desc, i ? "sphere" : "ground"));
  }
  std::vector<rb::Instance> instances(1);
  instances[0].mesh = handles[0];
  uint64_t triangles = cpu[0].triangleCount();
  for (int i = 0; i < 9; ++i) {
    rb::Instance inst;
    inst.mesh = handles[1];
    inst.customIndex = uint32_t(i + 1);
    Transform t = translation(-30.0f + 30.0f * float(i % 3), 6.0f, -30.0f + 30.0f * float(i / 3));
    setTransform(inst, t);
    instances.push_back(inst);
    triangles += cpu[1].triangleCount();
  }
  (void)buildQueued(env, *service);
  env.runFrame([&](VkCommandBuffer cmd) { (void)check(service->recordPendingWork(cmd), "compaction frame"); });
  env.settle();
  rb::TlasInfo tlas;
  env.runFrame([&](VkCommandBuffer cmd) { tlas = check(service->recordTlasBuild(cmd, instances), "TLAS"); });
  env.settle();

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
  rb::PrimaryRayCamera sky;
  sky.eye[1] = 20.0f;
  sky.target[1] = 100.0f;
  sky.target[2] = -10.0f;
  const std::pair<const char*, rb::PrimaryRayCamera> views[] = {{"ground + spheres", cameraOverGround(size)},
                                                                {"sky (all miss)", sky}};
  for (const auto& [name, camera] : views) {
    env.progress(std::string("trace: ") + name);
    TraceTiming t = timeTraces(env, *pass, tlas.tlas, camera, z.traceRepeats);
    table.add({{"view", name},
               {"triangles", triangles},
               {"rays", uint64_t(z.width) * z.height},
               {"medianMs", t.medianMs},
               {"minMs", t.minMs},
               {"allMs", t.ms},
               {"mraysPerSecond", t.raysPerSecond * 1e-6},
               {"graysPerSecond", t.raysPerSecond * 1e-9},
               {"hitFraction", t.hitFraction}});
  }
  table.print();
  pass.reset();
  service.reset();
  for (UploadedMesh& m : meshes) env.destroy(m);
  const auto& rows = table.rows();
  nlohmann::json summary = {{"missOverHitRate", ratio(rows[1]["mraysPerSecond"], rows[0]["mraysPerSecond"])}};
  printSummary(summary);
  return {{"width", z.width}, {"height", z.height}, {"rows", rows}, {"summary", summary}};
}

}  // namespace rbbench
