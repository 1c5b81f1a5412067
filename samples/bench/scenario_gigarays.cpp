// gigarays: the thesis's raw trace-rate scenarios. "stress": many rays per pixel (64 on a GPU) from a camera
// over a finely tessellated ground, every ray hits; "miss": the same rays towards an empty sky. Only the hit
// count is written, so the time is the tracing itself. The rays are counted from the written hit counts
// (stress must report every ray as a hit, miss none), not inferred from the settings.
#include <numeric>

#include "context_impl.h"
#include "gpu_memory.h"
#include "gpu_timer.h"
#include "ray_tracing_pipeline.h"
#include "report.h"
#include "scenarios.h"
#include "scene_meshes.h"
#include "service_frames.h"
#include "stress_shaders.h"

namespace rbbench {

namespace {

struct StressConstants {
  float eye[4], right[4], up[4], forward[4];
  uint32_t size[2];
  uint32_t raysPerPixel;
  uint32_t seed;
};

uint64_t sumHits(BenchEnv& env, const rb::GpuImage& image) {
  const VkDeviceSize bytes = VkDeviceSize(image.width) * image.height * 4;
  rb::HeadlessBuffer staging = check(env.device().createBuffer(bytes, VK_BUFFER_USAGE_TRANSFER_DST_BIT, true),
                                     "creating a readback buffer");
  VkCommandBuffer cmd = check(env.device().beginCommands(), "beginning a readback");
  VkImageMemoryBarrier b{VK_STRUCTURE_TYPE_IMAGE_MEMORY_BARRIER};
  b.srcAccessMask = VK_ACCESS_SHADER_WRITE_BIT;
  b.dstAccessMask = VK_ACCESS_TRANSFER_READ_BIT;
  b.oldLayout = b.newLayout = VK_IMAGE_LAYOUT_GENERAL;
  b.srcQueueFamilyIndex = b.dstQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED;
  b.image = image.image;
  b.subresourceRange = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 1, 0, 1};
  env.vk().vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_RAY_TRACING_SHADER_BIT_KHR, VK_PIPELINE_STAGE_TRANSFER_BIT, 0, 0,
                                nullptr, 0, nullptr, 1, &b);
  VkBufferImageCopy region{};
  region.imageSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 0, 1};
  region.imageExtent = {image.width, image.height, 1};
  env.vk().vkCmdCopyImageToBuffer(cmd, image.image, VK_IMAGE_LAYOUT_GENERAL, staging.buffer, 1, &region);
  check(env.device().submitAndWait(cmd), "reading back the hit counts");
  const uint32_t* counts = static_cast<const uint32_t*>(staging.mapped);
  uint64_t sum = std::accumulate(counts, counts + size_t(image.width) * image.height, uint64_t(0));
  env.device().destroyBuffer(staging);
  return sum;
}

}  // namespace

nlohmann::json runGigaRaysScenario(BenchEnv& env) {
  const BenchSizes& z = env.sizes();
  const uint32_t w = z.width, h = z.height;
  // 64 per pixel as in the thesis on a GPU; on a CPU implementation a few keep the run short.
  const uint32_t raysPerPixel = env.info().isCpu ? 4u : 64u;
  const float size = 100.0f;
  rbsamples::CpuMesh ground = groundWithAbout(z.traceTriangles, size);
  auto service = check(rb::AccelerationStructureService::create(env.ctx()), "creating the AS service");
  UploadedMesh mesh = env.upload(ground, "stress ground");
  rb::Instance instance;
  instance.mesh = registerOrThrow(*service, mesh.desc, "stress ground");
  (void)buildQueued(env, *service);
  rb::TlasInfo tlas;
  env.runFrame([&](VkCommandBuffer cmd) {
    tlas = check(service->recordTlasBuild(cmd, std::span(&instance, 1), kStaticTlas), "TLAS");
  });
  env.settle();

  rb::RayTracingPipelineDesc desc;
  desc.name = "gigarays stress";
  desc.raygen = rb::SpirvModule::of(rbbench::spirv::stress_rgen);
  desc.misses = {rb::SpirvModule::of(rbbench::spirv::stress_rmiss)};
  desc.hitGroups = {rb::HitGroupDesc{rb::SpirvModule::of(rbbench::spirv::stress_rchit), {}}};
  desc.bindings = {{0, VK_DESCRIPTOR_TYPE_ACCELERATION_STRUCTURE_KHR, 1, VK_SHADER_STAGE_RAYGEN_BIT_KHR, nullptr},
                   {1, VK_DESCRIPTOR_TYPE_STORAGE_IMAGE, 1, VK_SHADER_STAGE_RAYGEN_BIT_KHR, nullptr}};
  desc.pushConstantBytes = sizeof(StressConstants);
  rb::RayTracingPipeline pipeline = check(rb::RayTracingPipeline::create(env.ctx(), desc),
                                          "creating the stress pipeline");
  rb::GpuImage hits = check(rb::createStorageImage(env.ctx(), w, h, VK_FORMAT_R32_UINT, VK_IMAGE_USAGE_TRANSFER_SRC_BIT,
                                                   rb::MemoryCategory::PassImages, "stress hit counts"),
                            "creating the hit count image");

  Table table("gigarays: " + std::to_string(raysPerPixel) + " rays per pixel at " + std::to_string(w) + "x" +
                  std::to_string(h) + " (thesis stress and miss scenarios), median of " +
                  std::to_string(z.traceRepeats),
              {{"scenario", "scenario"},
               {"rays", "rays"},
               {"hit rays", "hitRays"},
               {"median ms", "medianMs", 3},
               {"GRays/s", "graysPerSecond", 3}});
  rb::PrimaryRayCamera sky;
  sky.eye[1] = 20.0f;
  sky.target[1] = 100.0f;
  sky.target[2] = -10.0f;
  const std::pair<const char*, rb::PrimaryRayCamera> views[] = {{"stress (all hit)", cameraOverGround(size)},
                                                                {"miss (all miss)", sky}};
  bool inGeneral = false;
  for (const auto& [name, camera] : views) {
    env.progress(std::string("gigarays: ") + name);
    rb::CameraBasis basis = check(rb::computeCameraBasis(camera, w, h), "camera");
    StressConstants pc{};
    for (int i = 0; i < 3; ++i) {
      pc.eye[i] = basis.eye[i];
      pc.right[i] = basis.right[i];
      pc.up[i] = basis.up[i];
      pc.forward[i] = basis.forward[i];
    }
    pc.size[0] = w;
    pc.size[1] = h;
    pc.raysPerPixel = raysPerPixel;
    GpuTimer timer(env, 2 * z.traceRepeats);
    std::vector<std::pair<uint32_t, uint32_t>> marks;
    env.runFrame([&](VkCommandBuffer cmd) {
      timer.reset(cmd);
      for (uint32_t i = 0; i <= z.traceRepeats; ++i) {
        VkImageMemoryBarrier b{VK_STRUCTURE_TYPE_IMAGE_MEMORY_BARRIER};
        b.srcAccessMask = VK_ACCESS_SHADER_WRITE_BIT;
        b.dstAccessMask = VK_ACCESS_SHADER_WRITE_BIT;
        b.oldLayout = inGeneral ? VK_IMAGE_LAYOUT_GENERAL : VK_IMAGE_LAYOUT_UNDEFINED;
        b.newLayout = VK_IMAGE_LAYOUT_GENERAL;
        b.srcQueueFamilyIndex = b.dstQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED;
        b.image = hits.image;
        b.subresourceRange = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 1, 0, 1};
        env.vk().vkCmdPipelineBarrier(cmd,
                                      VK_PIPELINE_STAGE_RAY_TRACING_SHADER_BIT_KHR | VK_PIPELINE_STAGE_TRANSFER_BIT,
                                      VK_PIPELINE_STAGE_RAY_TRACING_SHADER_BIT_KHR, 0, 0, nullptr, 0, nullptr, 1, &b);
        inGeneral = true;
        pc.seed = i;
        rb::DescriptorWrites writes;
        writes.accelerationStructure(0, tlas.tlas);
        writes.storageImage(1, hits.view);
        uint32_t a = i ? timer.mark(cmd) : 0;
        pipeline.bind(env.ctx(), cmd, writes.writes, &pc, sizeof pc);
        pipeline.trace(env.ctx(), cmd, w, h);
        if (i) marks.emplace_back(a, timer.mark(cmd));
      }
    });
    timer.resolve();
    std::vector<double> ms;
    for (auto [a, b] : marks) ms.push_back(timer.ms(a, b));
    double med = median(ms);
    uint64_t rays = uint64_t(w) * h * raysPerPixel;
    uint64_t hitRays = sumHits(env, hits);
    table.add({{"scenario", name},
               {"rays", rays},
               {"hitRays", hitRays},
               {"medianMs", med},
               {"allMs", ms},
               {"graysPerSecond", med > 0 ? double(rays) / (med * 1e-3) * 1e-9 : 0.0}});
  }
  table.print();
  env.settle();
  rb::destroyImage(env.ctx(), hits);
  pipeline.destroy(env.ctx());
  service.reset();
  env.destroy(mesh);
  const auto& rows = table.rows();
  nlohmann::json summary = {{"raysPerPixel", raysPerPixel},
                            {"stressGRaysPerSecond", rows[0]["graysPerSecond"]},
                            {"missGRaysPerSecond", rows[1]["graysPerSecond"]},
                            {"stressAllHit", rows[0]["hitRays"] == rows[0]["rays"]},
                            {"missAllMiss", rows[1]["hitRays"] == 0}};
  printSummary(summary);
  return {{"width", w}, {"height", h}, {"rows", rows}, {"summary", summary}};
}

}  // namespace rbbench
