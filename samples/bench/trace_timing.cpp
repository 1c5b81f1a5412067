#include "trace_timing.h"

#include "gpu_timer.h"
#include "report.h"

namespace rbbench {

TraceTiming timeTraces(BenchEnv& env, rb::PrimaryRayPass& pass, VkAccelerationStructureKHR tlas,
                       const rb::PrimaryRayCamera& camera, uint32_t repeats) {
  const uint32_t w = env.sizes().width, h = env.sizes().height;
  BenchEnv::TraceTargets targets = env.makeTraceTargets(w, h);
  GpuTimer timer(env, 2 * repeats);
  std::vector<std::pair<uint32_t, uint32_t>> marks;
  env.runFrame([&](VkCommandBuffer cmd) {
    timer.reset(cmd);
    for (uint32_t i = 0; i <= repeats; ++i) {
      env.recordTraceBarrier(cmd, targets);
      uint32_t a = i ? timer.mark(cmd) : 0;
      check(pass.record(cmd, {.tlas = rb::TlasInfo{.tlas = tlas},
                              .camera = camera,
                              .targets = {targets.distance.view, targets.ids.view, w, h}}),
            "PrimaryRayPass::record");
      if (i) marks.emplace_back(a, timer.mark(cmd));
    }
  });
  timer.resolve();
  TraceTiming t;
  for (auto [a, b] : marks) t.ms.push_back(timer.ms(a, b));
  t.medianMs = median(t.ms);
  t.minMs = minimum(t.ms);
  t.hitFraction = env.hitFraction(targets);
  t.raysPerSecond = t.medianMs > 0 ? double(w) * h / (t.medianMs * 1e-3) : 0.0;
  env.settle();
  env.destroyTraceTargets(targets);
  return t;
}

}  // namespace rbbench
