// Primary-ray trace time measured with the bench's own timestamps around PrimaryRayPass::record.
#pragma once

#include <raybridge/raybridge.h>

#include <vector>

#include "bench_env.h"

namespace rbbench {

struct TraceTiming {
  std::vector<double> ms;  // one per timed trace
  double medianMs = 0.0;
  double minMs = 0.0;
  double hitFraction = 0.0;    // of the last trace's pixels
  double raysPerSecond = 0.0;  // width * height / median time
};

// Records `repeats` traces of `tlas` at the bench resolution in one frame, each between two timestamps, after
// one untimed warm-up trace. The TLAS must be built and ready (recorded in an earlier, completed frame).
TraceTiming timeTraces(BenchEnv& env, rb::PrimaryRayPass& pass, VkAccelerationStructureKHR tlas,
                       const rb::PrimaryRayCamera& camera, uint32_t repeats);

}  // namespace rbbench
