// Per-pass measurement: GPU time from timestamp queries and the number of rays traced, counted on the GPU,
// one slot per frame in flight, read back once the frame is known to be done.
#pragma once

#include <raybridge/effects.h>

#include <vector>

#include "gpu_memory.h"
#include "raybridge_shader_interface.glsl"

namespace rb {

class PassMetrics {
 public:
  // Rays are summed into 4096 counters, one per pixel of a 64x64 tile: neighbouring invocations (one warp or
  // subgroup) never add to the same address, so the atomics do not serialise (shaders/ray_counters.glsl).
  // Any-hit invocations follow in as many counters, then a tile classifier's counts (ray_counters.glsl).
  static constexpr uint32_t kCounterSlots = RB_RAY_COUNTER_SLOTS;
  static constexpr uint32_t kCountersPerFrame = 2 * kCounterSlots + RB_RAY_COUNTER_TILE_UINTS;
  static_assert(kCountersPerFrame * sizeof(uint32_t) % 256 == 0, "each frame's counters start 256-byte aligned");

  // `countsRays` = false (the denoiser): GPU time only, no counter buffers.
  Status init(Context& ctx, const char* passName, bool countsRays = true);
  // Hands the counter buffer and the query pool to the context's deferred release (frames in flight may still
  // write them).
  void retire(Context& ctx);

  // Collects finished frames, then clears this frame's counters on the GPU (a fill behind a barrier). Call before
  // recording the pass, outside a render pass. Fails, recording nothing, when a finished frame's timestamps cannot
  // be read (a lost device); the error names the read.
  Status beginRecording(Context& ctx, VkCommandBuffer cmd);
  void writeStart(Context& ctx, VkCommandBuffer cmd);
  // The end timestamp, then the copy of this frame's counters to the host-visible readback buffer.
  void writeEnd(Context& ctx, VkCommandBuffer cmd);
  // Rays the pass knows without counting them on the GPU (a launch of one ray per pixel): added to this frame's
  // count. A shader atomic per ray costs a measurable share of a one-ray pass (docs/performance.md). Call between
  // beginRecording() and the frame's end; a later beginRecording() in the same frame starts again from 0.
  void addHostRays(Context& ctx, uint64_t rays);
  // The counter buffer of this frame's slot, for the shader's ray counters.
  VkBuffer counterBuffer() const { return counters_.buffer; }
  VkDeviceSize counterOffset(Context& ctx) const;
  VkDeviceSize counterBytes() const { return kCountersPerFrame * sizeof(uint32_t); }
  // Collects finished frames first (a frame whose timestamps cannot be read keeps gpuMs 0).
  const PassStats& latest(Context& ctx) {
    collect(ctx);
    return latest_;
  }

 private:
  void collect(Context& ctx);
  // The shaders' atomics go to device-local memory: atomics on host-visible memory cross the bus on a discrete
  // GPU (one per pixel, which made them a measurable part of a pass; docs/performance.md). The host reads the
  // copy in readback_ once the frame is done. Both hold framesInFlight * kCountersPerFrame uints.
  GpuBuffer counters_;
  GpuBuffer readback_;
  VkQueryPool timestamps_ = VK_NULL_HANDLE;
  std::vector<uint64_t> recordedFrame_;  // per slot; UINT64_MAX = nothing pending
  std::vector<uint64_t> hostRays_;       // per slot: addHostRays() since the slot's beginRecording()
  PassStats latest_;
  bool timing_ = false;
  const char* name_ = "";  // the pass, for errors
  Status readError_;       // a failed read of finished timestamps, for the next beginRecording() to report
};

}  // namespace rb
