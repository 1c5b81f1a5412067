// fastbuild-vs-fasttrace: one finely tessellated ground registered as MeshRole::Static (PREFER_FAST_TRACE) and
// as MeshRole::Dynamic (PREFER_FAST_BUILD); build time from the service's timestamps, trace time from the
// bench's own timestamps around PrimaryRayPass::record.
#include "gpu_timer.h"
#include "report.h"
#include "scenarios.h"
#include "scene_meshes.h"
#include "service_frames.h"
#include "trace_timing.h"

namespace rbbench {

namespace {

constexpr float kGroundSize = 100.0f;

nlohmann::json measure(BenchEnv& env, rb::PrimaryRayPass& pass, const UploadedMesh& mesh, rb::MeshRole role) {
  const bool dynamic = role == rb::MeshRole::Dynamic;
  const std::string name = dynamic ? "Dynamic" : "Static";
  std::vector<double> ms;
  std::unique_ptr<rb::AccelerationStructureService> service;
  rb::Instance instance;
  for (uint32_t r = 0; r < env.sizes().fastRepeats; ++r) {
    service.reset();
    service = check(rb::AccelerationStructureService::create(env.ctx()), "creating the AS service");
    rb::MeshDesc d = mesh.desc;
    d.role = role;
    instance.mesh = registerOrThrow(*service, d, "ground (" + name + ")");
    ms.push_back(buildQueued(env, *service).gpuMs);
  }
  rb::TlasInfo tlas;
  env.runFrame([&](VkCommandBuffer cmd) {
    tlas = check(service->recordTlasBuild(cmd, {&instance, 1}, kStaticTlas), "TLAS");
  });
  env.settle();
  TraceTiming trace = timeTraces(env, pass, tlas.tlas, cameraOverGround(kGroundSize), env.sizes().traceRepeats);
  rb::AsStats st = service->stats();
  const double med = warmMedian(ms);
  return {{"role", name},
          {"flags", dynamic ? "PREFER_FAST_BUILD|ALLOW_UPDATE" : "PREFER_FAST_TRACE|ALLOW_COMPACTION"},
          {"triangles", mesh.triangles},
          {"buildFirstMs", ms.front()},
          {"buildMedianMs", med},
          {"buildAllMs", ms},
          {"mtrisPerSecond", med > 0 ? double(mesh.triangles) / (med * 1e3) : 0.0},
          {"blasBytes", st.blasBytesBeforeCompaction},
          {"traceMedianMs", trace.medianMs},
          {"traceAllMs", trace.ms},
          {"mraysPerSecond", trace.raysPerSecond * 1e-6},
          {"hitFraction", trace.hitFraction}};
}

}  // namespace

nlohmann::json runFastBuildScenario(BenchEnv& env) {
  const BenchSizes& z = env.sizes();
  rbsamples::CpuMesh cpu = groundWithAbout(z.fastTriangles, kGroundSize);
  UploadedMesh mesh = env.upload(cpu, "ground");
  auto pass = check(rb::PrimaryRayPass::create(env.ctx()), "creating the primary ray pass");
  env.progress("fastbuild-vs-fasttrace: " + std::to_string(cpu.triangleCount()) + " triangles");
  nlohmann::json fastTrace = measure(env, *pass, mesh, rb::MeshRole::Static);
  nlohmann::json fastBuild = measure(env, *pass, mesh, rb::MeshRole::Dynamic);
  Table table("fastbuild-vs-fasttrace: ground of " + std::to_string(cpu.triangleCount()) + " triangles, " +
                  std::to_string(z.width) + "x" + std::to_string(z.height) + " primary rays",
              {{"role", "role"},
               {"flags", "flags"},
               {"build first ms", "buildFirstMs", 3},
               {"build median ms", "buildMedianMs", 3},
               {"Mtris/s", "mtrisPerSecond", 1},
               {"BLAS bytes", "blasBytes"},
               {"trace ms", "traceMedianMs", 3},
               {"Mrays/s", "mraysPerSecond", 2},
               {"hits", "hitFraction", 2}});
  table.add(fastTrace);
  table.add(fastBuild);
  table.print();
  nlohmann::json summary = {
      {"buildFastTraceOverFastBuild", ratio(fastTrace["buildMedianMs"], fastBuild["buildMedianMs"])},
      {"traceFastBuildOverFastTrace", ratio(fastBuild["traceMedianMs"], fastTrace["traceMedianMs"])},
      {"bytesFastTraceOverFastBuild", ratio(fastTrace["blasBytes"], fastBuild["blasBytes"])}};
  printSummary(summary);
  env.destroy(mesh);
  return {{"rows", table.rows()}, {"summary", summary}};
}

}  // namespace rbbench
