// compaction: BLAS bytes as built and after the service's compaction (AsStats::blasBytesBeforeCompaction vs
// blasBytes), how many BLASes were compacted or skipped (saving < 2%), bytes per triangle, and the GPU time of
// the frame that records the compaction copies.
#include "gpu_timer.h"
#include "report.h"
#include "scenarios.h"
#include "service_frames.h"

namespace rbbench {

namespace {

nlohmann::json measure(BenchEnv& env, std::vector<UploadedMesh>& meshes, const std::string& name) {
  auto service = check(rb::AccelerationStructureService::create(env.ctx()), "creating the AS service");
  for (size_t i = 0; i < meshes.size(); ++i) registerOrThrow(*service, meshes[i].desc, name + "#" + std::to_string(i));
  BatchSum build = buildQueued(env, *service);
  // The compacted sizes resolved when the build frame settled; this frame records the copies.
  GpuTimer timer(env, 2);
  uint32_t a = 0, b = 0;
  env.runFrame([&](VkCommandBuffer cmd) {
    timer.reset(cmd);
    a = timer.mark(cmd);
    (void)check(service->recordPendingWork(cmd), "recordPendingWork (compaction)");
    b = timer.mark(cmd);
  });
  timer.resolve();
  env.settle();
  rb::AsStats st = service->stats();
  const double tris = double(st.triangles);
  return {{"mesh", name},
          {"blas", st.blasCount},
          {"triangles", st.triangles},
          {"bytesBuilt", st.blasBytesBeforeCompaction},
          {"bytesAfter", st.blasBytes},
          {"afterOverBuilt", ratio(double(st.blasBytes), double(st.blasBytesBeforeCompaction))},
          {"bytesPerTriangleBuilt", tris > 0 ? double(st.blasBytesBeforeCompaction) / tris : 0.0},
          {"bytesPerTriangleAfter", st.bytesPerTriangle},
          {"compacted", st.blasCompacted},
          {"skipped", st.compactionsSkipped},
          {"buildGpuMs", build.gpuMs},
          {"copyFrameGpuMs", timer.ms(a, b)}};
}

}  // namespace

nlohmann::json runCompactionScenario(BenchEnv& env, const std::vector<GltfModel>& models) {
  const BenchSizes& z = env.sizes();
  Table table("compaction: BLAS bytes as built and after compaction", {{"mesh", "mesh"},
                                                                       {"BLAS", "blas"},
                                                                       {"triangles", "triangles"},
                                                                       {"built bytes", "bytesBuilt"},
                                                                       {"after bytes", "bytesAfter"},
                                                                       {"after/built", "afterOverBuilt", 3},
                                                                       {"B/tri built", "bytesPerTriangleBuilt", 1},
                                                                       {"B/tri after", "bytesPerTriangleAfter", 1},
                                                                       {"compacted", "compacted"},
                                                                       {"skipped", "skipped"},
                                                                       {"copy frame ms", "copyFrameGpuMs", 3}});
  for (uint64_t target : z.buildTriangles) {
    const std::string name = "sphere " + humanCount(target);
    env.progress("compaction: " + name);
    rbsamples::CpuMesh cpu = rbsamples::makeSphereWithAbout(target, 1.0f);
    std::vector<UploadedMesh> meshes = {env.upload(cpu, name)};
    table.add(measure(env, meshes, name));
    env.destroy(meshes[0]);
  }
  for (const GltfModel& m : models) {
    env.progress("compaction: glTF " + m.name);
    std::vector<UploadedMesh> meshes;
    for (const auto& cpu : m.meshes) meshes.push_back(env.upload(cpu, m.name));
    table.add(measure(env, meshes, "gltf " + m.name));
    for (UploadedMesh& u : meshes) env.destroy(u);
  }
  table.print();
  uint64_t built = 0, after = 0, compacted = 0, skipped = 0;
  for (const auto& r : table.rows()) {
    built += r["bytesBuilt"].get<uint64_t>();
    after += r["bytesAfter"].get<uint64_t>();
    compacted += r["compacted"].get<uint64_t>();
    skipped += r["skipped"].get<uint64_t>();
  }
  nlohmann::json summary = {{"totalAfterOverBuilt", ratio(double(after), double(built))},
                            {"compacted", compacted},
                            {"skipped", skipped}};
  printSummary(summary);
  return {{"rows", table.rows()}, {"summary", summary}};
}

}  // namespace rbbench
