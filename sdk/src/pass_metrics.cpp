#include "pass_metrics.h"

#include <cstring>
#include <string>

#include "context_impl.h"

namespace rb {

Status PassMetrics::init(Context& ctx, const char* passName) {
  Context::Impl& c = internal::contextImpl(ctx);
  const uint32_t slots = c.desc.framesInFlight;
  Result<GpuBuffer> b = createBuffer(ctx, VkDeviceSize(slots) * kCountersPerFrame * sizeof(uint32_t),
                                     VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | VK_BUFFER_USAGE_TRANSFER_DST_BIT,
                                     MemoryLocation::HostVisible, MemoryCategory::PassBuffers, passName);
  if (!b) return b.error();
  counters_ = b.value();
  std::memset(counters_.mapped, 0, counters_.size);
  recordedFrame_.assign(slots, UINT64_MAX);
  timing_ = c.info.timestampsSupported;
  if (timing_) {
    VkQueryPoolCreateInfo qi{VK_STRUCTURE_TYPE_QUERY_POOL_CREATE_INFO};
    qi.queryType = VK_QUERY_TYPE_TIMESTAMP;
    qi.queryCount = 2 * slots;
    VkResult r = c.vk.vkCreateQueryPool(c.desc.device, &qi, c.allocator(), &timestamps_);
    if (r != VK_SUCCESS) return vulkanError(r, std::string("vkCreateQueryPool for ") + passName);
  }
  return {};
}

void PassMetrics::retire(Context& ctx) {
  internal::contextImpl(ctx).retireHandle(timestamps_, &DeviceFunctions::vkDestroyQueryPool);
  retireBuffer(ctx, counters_);
  recordedFrame_.assign(recordedFrame_.size(), UINT64_MAX);
}

VkDeviceSize PassMetrics::counterOffset(Context& ctx) const {
  return (ctx.frameIndex() % ctx.framesInFlight()) * counterBytes();
}

void PassMetrics::collect(Context& ctx) {
  Context::Impl& c = internal::contextImpl(ctx);
  for (uint32_t slot = 0; slot < recordedFrame_.size(); ++slot) {
    uint64_t f = recordedFrame_[slot];
    if (f == UINT64_MAX || !c.frameDone(f)) continue;
    PassStats s;
    s.frame = f;
    const uint32_t* counts = reinterpret_cast<const uint32_t*>(static_cast<const uint8_t*>(counters_.mapped) +
                                                               slot * counterBytes());
    for (uint32_t i = 0; i < kCounterSlots; ++i) s.rays += counts[i];
    for (uint32_t i = 0; i < kCounterSlots; ++i) s.anyHitInvocations += counts[kCounterSlots + i];
    s.tilesTraced = counts[2 * kCounterSlots];  // RayCounters::tilesTraced, then tilesSkipped
    s.tilesSkipped = counts[2 * kCounterSlots + 1];
    if (timing_) {
      uint64_t ticks[2] = {0, 0};
      if (c.vk.vkGetQueryPoolResults(c.desc.device, timestamps_, 2 * slot, 2, sizeof ticks, ticks, sizeof(uint64_t),
                                     VK_QUERY_RESULT_64_BIT) == VK_SUCCESS) {
        s.gpuMs = double(c.info.timestampTicks(ticks[0], ticks[1])) * c.info.timestampPeriodNs * 1e-6;
      }
    }
    if (s.frame >= latest_.frame) latest_ = s;
    recordedFrame_[slot] = UINT64_MAX;
  }
}

void PassMetrics::beginRecording(Context& ctx, VkCommandBuffer cmd) {
  collect(ctx);
  Context::Impl& c = internal::contextImpl(ctx);
  const uint32_t slot = static_cast<uint32_t>(c.frame % c.desc.framesInFlight);
  // The slot's previous frame is done (beginFrame contract), so the host may clear its counters now.
  std::memset(static_cast<uint8_t*>(counters_.mapped) + slot * counterBytes(), 0, counterBytes());
  recordedFrame_[slot] = c.frame;
  if (timing_) c.vk.vkCmdResetQueryPool(cmd, timestamps_, 2 * slot, 2);
}

void PassMetrics::writeStart(Context& ctx, VkCommandBuffer cmd) {
  if (!timing_) return;
  const uint32_t slot = static_cast<uint32_t>(ctx.frameIndex() % ctx.framesInFlight());
  internal::deviceFunctions(ctx).vkCmdWriteTimestamp(cmd, VK_PIPELINE_STAGE_ALL_COMMANDS_BIT, timestamps_, 2 * slot);
}

void PassMetrics::writeEnd(Context& ctx, VkCommandBuffer cmd) {
  if (!timing_) return;
  const uint32_t slot = static_cast<uint32_t>(ctx.frameIndex() % ctx.framesInFlight());
  internal::deviceFunctions(ctx).vkCmdWriteTimestamp(cmd, VK_PIPELINE_STAGE_ALL_COMMANDS_BIT, timestamps_,
                                                     2 * slot + 1);
}

}  // namespace rb
