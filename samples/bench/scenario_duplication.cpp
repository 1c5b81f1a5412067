// duplication: one mesh copied N times in a grid, (a) each copy its own BLAS (distinct contentKey over the same
// buffers, as an engine that loads the model N times would get), (b) shared through dedup (one BLAS, N
// instances). Memory, build, TLAS and trace cost of both.
#include "gpu_timer.h"
#include "report.h"
#include "scenarios.h"
#include "scene_meshes.h"
#include "service_frames.h"
#include "trace_timing.h"

namespace rbbench {

namespace {

nlohmann::json measure(BenchEnv& env, rb::PrimaryRayPass& pass, const UploadedMesh& mesh, const Bounds& meshBounds,
                       uint32_t copies, bool shared) {
  auto service = check(rb::AccelerationStructureService::create(env.ctx()), "creating the AS service");
  const float extent = std::max(meshBounds.max[0] - meshBounds.min[0], meshBounds.max[2] - meshBounds.min[2]);
  std::vector<Transform> placement = gridPlacement(copies, extent * 1.25f);
  std::vector<rb::Instance> instances(copies);
  Bounds scene;
  for (uint32_t i = 0; i < copies; ++i) {
    rb::MeshDesc d = mesh.desc;
    d.contentKey = shared ? 0x5eed : 0x5eed + 1 + i;
    instances[i].mesh = registerOrThrow(*service, d, "copy " + std::to_string(i));
    instances[i].customIndex = i;
    setTransform(instances[i], placement[i]);
    Bounds b = meshBounds;
    for (int r = 0; r < 3; ++r) {
      b.min[r] += placement[i][4 * r + 3];
      b.max[r] += placement[i][4 * r + 3];
    }
    scene.add(b);
  }
  BatchSum build = buildQueued(env, *service);
  env.runFrame([&](VkCommandBuffer cmd) { (void)check(service->recordPendingWork(cmd), "compaction frame"); });
  env.settle();

  GpuTimer timer(env, 2);
  rb::TlasInfo tlas;
  uint32_t a = 0, b = 0;
  env.runFrame([&](VkCommandBuffer cmd) {
    timer.reset(cmd);
    a = timer.mark(cmd);
    tlas = check(service->recordTlasBuild(cmd, instances, kStaticTlas), "recordTlasBuild");
    b = timer.mark(cmd);
  });
  timer.resolve();
  if (tlas.skippedInstances) throw BenchFailure("duplication: the TLAS skipped instances");
  TraceTiming trace = timeTraces(env, pass, tlas.tlas, cameraFraming(scene), env.sizes().traceRepeats);
  rb::AsStats st = service->stats();
  return {{"copies", copies},
          {"mode", shared ? "dedup" : "distinct"},
          {"blasCount", st.blasCount},
          {"dedupHits", st.dedupHits},
          {"triangles", st.triangles},
          {"blasBytesBuilt", st.blasBytesBeforeCompaction},
          {"blasBytes", st.blasBytes},
          {"buildGpuMs", build.gpuMs},
          {"buildBatches", build.batches},
          {"timingComplete", build.complete},
          {"tlasGpuMs", timer.ms(a, b)},
          {"traceMs", trace.medianMs},
          {"hitFraction", trace.hitFraction}};
}

}  // namespace

nlohmann::json runDuplicationScenario(BenchEnv& env) {
  const BenchSizes& z = env.sizes();
  rbsamples::CpuMesh cpu = rbsamples::makeSphereWithAbout(z.duplicationTriangles, 1.0f);
  UploadedMesh mesh = env.upload(cpu, "duplicated sphere");
  Bounds bounds = boundsOf(cpu);
  auto pass = check(rb::PrimaryRayPass::create(env.ctx()), "creating the primary ray pass");
  Table table("duplication: sphere of " + std::to_string(cpu.triangleCount()) + " triangles copied N times, " +
                  std::to_string(z.width) + "x" + std::to_string(z.height) + " primary rays",
              {{"N", "copies"},
               {"mode", "mode"},
               {"BLAS", "blasCount"},
               {"BLAS bytes", "blasBytes"},
               {"build ms", "buildGpuMs", 3},
               {"TLAS ms", "tlasGpuMs", 3},
               {"trace ms", "traceMs", 3},
               {"hits", "hitFraction", 2}});
  nlohmann::json ratios = nlohmann::json::array();
  for (uint32_t n : z.duplicationCopies) {
    env.progress("duplication: N = " + std::to_string(n));
    nlohmann::json distinct = measure(env, *pass, mesh, bounds, n, false);
    nlohmann::json shared = measure(env, *pass, mesh, bounds, n, true);
    table.add(distinct);
    table.add(shared);
    ratios.push_back({{"copies", n},
                      {"bytesDistinctOverDedup", ratio(distinct["blasBytes"], shared["blasBytes"])},
                      {"buildDistinctOverDedup", ratio(distinct["buildGpuMs"], shared["buildGpuMs"])},
                      {"tlasDistinctOverDedup", ratio(distinct["tlasGpuMs"], shared["tlasGpuMs"])},
                      {"traceDistinctOverDedup", ratio(distinct["traceMs"], shared["traceMs"])}});
  }
  table.print();
  Table ratioTable("duplication: distinct / dedup ratios (same run)", {{"N", "copies"},
                                                                       {"bytes", "bytesDistinctOverDedup", 2},
                                                                       {"build", "buildDistinctOverDedup", 2},
                                                                       {"TLAS", "tlasDistinctOverDedup", 2},
                                                                       {"trace", "traceDistinctOverDedup", 2}});
  for (const auto& r : ratios) ratioTable.add(r);
  ratioTable.print();
  env.destroy(mesh);
  return {{"meshTriangles", cpu.triangleCount()}, {"rows", table.rows()}, {"ratios", ratios}};
}

}  // namespace rbbench
