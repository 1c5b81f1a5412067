// build: BLAS build GPU time (the service's own per-batch timestamps) against triangle count. Every repeat uses
// a fresh service, so each one is a real build, never a dedup hit. The first build of a process is reported
// apart: lavapipe is markedly slower on it.
#include "report.h"
#include "scenarios.h"
#include "service_frames.h"

namespace rbbench {

namespace {

struct BuildSample {
  std::vector<double> ms;
  uint64_t triangles = 0;
  uint32_t blasCount = 0;
  uint64_t blasBytes = 0;
  bool complete = true;
};

// Builds `meshes` (one BLAS each, all in one frame) `repeats` times, each in a fresh service.
BuildSample measure(BenchEnv& env, std::vector<UploadedMesh>& meshes, const std::string& name, uint32_t repeats) {
  BuildSample s;
  for (uint32_t r = 0; r < repeats; ++r) {
    auto service = check(rb::AccelerationStructureService::create(env.ctx()), "creating the AS service");
    for (size_t i = 0; i < meshes.size(); ++i)
      registerOrThrow(*service, meshes[i].desc, name + "#" + std::to_string(i));
    BatchSum sum = buildQueued(env, *service);
    s.ms.push_back(sum.gpuMs);
    s.triangles = sum.triangles;
    s.complete = s.complete && sum.complete;
    rb::AsStats st = service->stats();
    s.blasCount = st.blasCount;
    s.blasBytes = st.blasBytesBeforeCompaction;
  }
  return s;
}

nlohmann::json row(const std::string& name, uint32_t meshCount, const BuildSample& s) {
  const double med = warmMedian(s.ms);
  return {{"mesh", name},
          {"blas", meshCount},
          {"triangles", s.triangles},
          {"repeats", s.ms.size()},
          {"firstMs", s.ms.front()},
          {"medianMs", med},
          {"minMs", minimum(s.ms)},
          {"allMs", s.ms},
          {"mtrisPerSecond", med > 0 ? double(s.triangles) / (med * 1e3) : 0.0},
          {"firstOverMedian", ratio(s.ms.front(), med)},
          {"blasBytes", s.blasBytes},
          {"timingComplete", s.complete}};
}

}  // namespace

nlohmann::json runBuildScenario(BenchEnv& env, const std::vector<GltfModel>& models) {
  const BenchSizes& z = env.sizes();
  Table table("build: BLAS build GPU time (service timestamps; median of the repeats after the first)",
              {{"mesh", "mesh"},
               {"BLAS", "blas"},
               {"triangles", "triangles"},
               {"first ms", "firstMs", 3},
               {"median ms", "medianMs", 3},
               {"min ms", "minMs", 3},
               {"Mtris/s", "mtrisPerSecond", 1},
               {"first/median", "firstOverMedian", 2}});
  for (uint64_t target : z.buildTriangles) {
    const std::string name = "sphere " + humanCount(target);
    env.progress("build: " + name + ", " + std::to_string(z.buildRepeats) + " builds");
    rbsamples::CpuMesh cpu = rbsamples::makeSphereWithAbout(target, 1.0f);
    std::vector<UploadedMesh> meshes = {env.upload(cpu, name)};
    table.add(row(name, 1, measure(env, meshes, name, z.buildRepeats)));
    env.destroy(meshes[0]);
  }
  const uint32_t gltfRepeats = z.gltfRepeatsOnce ? 1 : std::min<uint32_t>(z.buildRepeats, 3);
  for (const GltfModel& m : models) {
    env.progress("build: glTF " + m.name);
    std::vector<UploadedMesh> meshes;
    for (size_t i = 0; i < m.meshes.size(); ++i) meshes.push_back(env.upload(m.meshes[i], m.name));
    table.add(row("gltf " + m.name, static_cast<uint32_t>(meshes.size()), measure(env, meshes, m.name, gltfRepeats)));
    for (UploadedMesh& u : meshes) env.destroy(u);
  }
  table.print();
  // Rate at the largest procedural size against the smallest: how far the build is from its asymptotic rate.
  nlohmann::json summary = nlohmann::json::object();
  const auto& rows = table.rows();
  const size_t n = z.buildTriangles.size();
  if (n >= 2) {
    summary["rateLargestOverSmallest"] = ratio(rows[n - 1]["mtrisPerSecond"], rows[0]["mtrisPerSecond"]);
    summary["largestMtrisPerSecond"] = rows[n - 1]["mtrisPerSecond"];
    summary["largestFirstOverMedian"] = rows[n - 1]["firstOverMedian"];
  }
  printSummary(summary);
  return {{"rows", rows}, {"summary", summary}};
}

}  // namespace rbbench
