// Frames that drive the acceleration-structure service the way an engine does, and the GPU times the service
// resolves for them (AsStats::batches, available once the frame has settled).
#pragma once

#include <raybridge/raybridge.h>

#include <span>

#include "bench_env.h"

namespace rbbench {

struct BatchSum {
  double gpuMs = 0.0;
  uint32_t batches = 0;
  uint32_t builds = 0;
  uint64_t triangles = 0;
  bool complete = true;  // false when fewer builds were timed than recorded (AsStats::batches keeps the last 64)
};
// Sums the service's build batches recorded in `frame`.
BatchSum batchesOfFrame(const rb::AsStats& stats, uint64_t frame);

// Records every queued build in one frame, waits, settles; returns the service's timing of that frame's batches.
// Throws when builds remain queued or the service resolved no timing for them; warns (complete = false) when
// it resolved timings for only some of them.
BatchSum buildQueued(BenchEnv& env, rb::AccelerationStructureService& service);

// Registers `desc` (debugName set from `name`) and throws on failure.
rb::MeshHandle registerOrThrow(rb::AccelerationStructureService& service, rb::MeshDesc desc, const std::string& name);

}  // namespace rbbench
