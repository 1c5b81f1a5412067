#include "service_frames.h"

#include <string>

namespace rbbench {

BatchSum batchesOfFrame(const rb::AsStats& stats, uint64_t frame) {
  BatchSum sum;
  for (const rb::BuildBatchTiming& t : stats.batches) {
    if (t.frame != frame) continue;
    sum.gpuMs += t.gpuMs;
    ++sum.batches;
    sum.builds += t.blasBuilds;
    sum.triangles += t.triangles;
  }
  return sum;
}

BatchSum buildQueued(BenchEnv& env, rb::AccelerationStructureService& service) {
  const uint32_t queued = service.stats().blasQueued;
  uint64_t frame = 0;
  uint32_t left = 0;
  env.runFrame([&](VkCommandBuffer cmd) {
    frame = env.ctx().frameIndex();
    left = check(service.recordPendingWork(cmd), "recordPendingWork");
  });
  if (left != 0) throw BenchFailure(std::to_string(left) + " BLAS builds stayed queued after recordPendingWork");
  env.settle();
  BatchSum sum = batchesOfFrame(service.stats(), frame);
  if (sum.batches == 0) {
    throw BenchFailure("the service resolved no build timing for frame " + std::to_string(frame) +
                       " (AsStats::batches)");
  }
  if (sum.builds != queued) {
    sum.complete = false;
    env.progress("warning: the service resolved timings for " + std::to_string(sum.builds) + " of " +
                 std::to_string(queued) + " builds of frame " + std::to_string(frame) +
                 " (AsStats::batches keeps the last 64 batches); the time is a lower bound");
  }
  return sum;
}

rb::MeshHandle registerOrThrow(rb::AccelerationStructureService& service, rb::MeshDesc desc, const std::string& name) {
  desc.debugName = name.c_str();
  rb::MeshHandle h = check(service.registerMesh(desc), "registerMesh(" + name + ")");
  return h;
}

}  // namespace rbbench
