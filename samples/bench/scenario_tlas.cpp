// tlas: a TLAS over 1k, 10k, 100k (GPU: 1M) instances of a few small meshes. Host time of recordTlasBuild
// (std::chrono; it writes the instance buffer) and GPU time of the build (the bench's own timestamps, the instance
// copy included where there is one), both as medians of repeated frames after one warm-up frame per frame slot,
// and per 1,000 instances. Each size is measured in four variants, one change at a time: a rebuild every frame
// (TlasBuildMode::Rebuild) reading the host-visible instances in place, reading a device-local copy (the default on a
// discrete GPU), the copy with a fast-build TLAS, and the copy refitting the previous frame's TLAS
// (TlasBuildMode::UpdateIfPossible) while every instance moves a little each frame (an engine's frame where the
// instance list keeps its meshes).
#include <chrono>

#include "gpu_timer.h"
#include "report.h"
#include "scenarios.h"
#include "scene_meshes.h"
#include "service_frames.h"

namespace rbbench {

nlohmann::json runTlasScenario(BenchEnv& env) {
  const BenchSizes& z = env.sizes();
  const float boxMin[3] = {-0.5f, -0.5f, -0.5f}, boxMax[3] = {0.5f, 0.5f, 0.5f};
  std::vector<rbsamples::CpuMesh> cpu = {rbsamples::makeSphere(0.5f, 16, 10), rbsamples::makeBox(boxMin, boxMax, 2),
                                         rbsamples::makeSphere(0.5f, 8, 6), rbsamples::makeGrid(1.0f, 4)};
  std::vector<UploadedMesh> meshes;
  for (const rbsamples::CpuMesh& m : cpu) meshes.push_back(env.upload(m, "tlas mesh"));
  // A service of its own per variant: TLAS buffers grown for the largest count of one variant would otherwise be
  // what the next one builds into.
  std::unique_ptr<rb::AccelerationStructureService> service;
  std::vector<rb::MeshHandle> handles;
  auto freshService = [&] {
    env.settle();
    service.reset();
    service = check(rb::AccelerationStructureService::create(env.ctx()), "creating the AS service");
    handles.clear();
    for (size_t i = 0; i < meshes.size(); ++i)
      handles.push_back(registerOrThrow(*service, meshes[i].desc, "tlas mesh " + std::to_string(i)));
    (void)buildQueued(env, *service);
  };

  Table table("tlas: TLAS over many instances (" + std::to_string(cpu.size()) + " meshes; median of " +
                  std::to_string(z.tlasRepeats) + " frames)",
              {{"variant", "variant"},
               {"instances", "instances"},
               {"host ms", "hostMedianMs", 3},
               {"host ms/1k", "hostMsPer1k", 4},
               {"GPU ms", "gpuMedianMs", 3},
               {"GPU ms/1k", "gpuMsPer1k", 4},
               {"TLAS bytes", "tlasBytes"}});
  GpuTimer timer(env, 2);
  struct Variant {
    const char* name;
    rb::TlasBuildOptions options;
    bool moving = false;  // every instance's translation changes each frame (a refit then has work to do)
  };
  const Variant variants[] = {
      {"in place", {.mode = rb::TlasBuildMode::Rebuild, .instanceUpload = rb::TlasInstanceUpload::ReadInPlace}},
      {"device copy", {.mode = rb::TlasBuildMode::Rebuild, .instanceUpload = rb::TlasInstanceUpload::CopyToDevice}},
      {"copy+fast build",
       {.mode = rb::TlasBuildMode::Rebuild,
        .instanceUpload = rb::TlasInstanceUpload::CopyToDevice,
        .preference = rb::TlasBuildPreference::FastBuild}},
      {"copy+update",
       {.mode = rb::TlasBuildMode::UpdateIfPossible, .instanceUpload = rb::TlasInstanceUpload::CopyToDevice},
       true}};
  for (const Variant& variant : variants) {
    freshService();
    for (uint32_t count : z.tlasInstances) {
      env.progress("tlas: " + humanCount(count) + " instances, " + variant.name);
      std::vector<Transform> placement = gridPlacement(count, 1.5f);
      std::vector<rb::Instance> instances(count);
      for (uint32_t i = 0; i < count; ++i) {
        instances[i].mesh = handles[i % handles.size()];
        instances[i].customIndex = i & 0xFFFFFFu;
        setTransform(instances[i], placement[i]);
      }
      std::vector<double> hostMs, gpuMs;
      const uint32_t warmup = env.ctx().framesInFlight();
      for (uint32_t f = 0; f < warmup + z.tlasRepeats; ++f) {
        if (variant.moving) {
          // Up to 0.06 units along y, a different phase per instance: every bound moves, none by much.
          for (uint32_t i = 0; i < count; ++i) instances[i].transform[7] = placement[i][7] + 0.01f * float((f + i) % 7);
        }
        double host = 0.0;
        uint32_t a = 0, b = 0;
        rb::TlasInfo info;
        env.runFrame([&](VkCommandBuffer cmd) {
          timer.reset(cmd);
          a = timer.mark(cmd);
          auto t0 = std::chrono::steady_clock::now();
          info = check(service->recordTlasBuild(cmd, instances, variant.options), "recordTlasBuild");
          host = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
          b = timer.mark(cmd);
        });
        timer.resolve();
        if (info.instanceCount != count) throw BenchFailure("tlas: the TLAS holds fewer instances than given");
        // After the warm-up frames the update variant must refit, or it measures rebuilds.
        if (variant.options.mode == rb::TlasBuildMode::UpdateIfPossible && f >= warmup && !info.updated)
          throw BenchFailure("tlas: copy+update rebuilt the TLAS instead of refitting it");
        if (f < warmup) continue;
        hostMs.push_back(host);
        gpuMs.push_back(timer.ms(a, b));
      }
      env.settle();
      const double host = median(hostMs), gpu = median(gpuMs);
      table.add({{"variant", variant.name},
                 {"instances", count},
                 {"hostMedianMs", host},
                 {"hostMsPer1k", host / (count / 1000.0)},
                 {"hostAllMs", hostMs},
                 {"gpuMedianMs", gpu},
                 {"gpuMsPer1k", gpu / (count / 1000.0)},
                 {"gpuAllMs", gpuMs},
                 {"tlasBytes", service->stats().tlasBytes}});
    }
  }
  table.print();
  env.settle();
  service.reset();
  for (UploadedMesh& m : meshes) env.destroy(m);
  const auto& rows = table.rows();
  nlohmann::json summary = nlohmann::json::object();
  // The summary compares sizes within the default variant (the device copy), and the variants at 10k instances.
  std::vector<nlohmann::json> copyRows;
  nlohmann::json at10k = nlohmann::json::object();
  for (const nlohmann::json& r : rows) {
    if (r["variant"] == "device copy") copyRows.push_back(r);
    if (r["instances"] == 10000) at10k[r["variant"].get<std::string>()] = r["gpuMedianMs"];
  }
  if (copyRows.size() >= 2) {
    summary["gpuPer1kLargestOverSmallest"] = ratio(copyRows.back()["gpuMsPer1k"], copyRows.front()["gpuMsPer1k"]);
    summary["hostPer1kLargestOverSmallest"] = ratio(copyRows.back()["hostMsPer1k"], copyRows.front()["hostMsPer1k"]);
    summary["hostOverGpuLargest"] = ratio(copyRows.back()["hostMedianMs"], copyRows.back()["gpuMedianMs"]);
  }
  if (!at10k.empty()) summary["gpuMsAt10kByVariant"] = at10k;
  printSummary(summary);
  return {{"rows", rows}, {"summary", summary}};
}

}  // namespace rbbench
