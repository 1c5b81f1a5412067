#include "pass_metrics.h"

#include <cstring>
#include <string>
#include <utility>

#include "context_impl.h"
#include "memory_barrier.h"

namespace rb {

namespace {

// The stages whose shaders add to the counters: ray tracing passes and compute passes.
constexpr VkPipelineStageFlags kCounterShaderStages = VK_PIPELINE_STAGE_RAY_TRACING_SHADER_BIT_KHR |
                                                      VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT;

}  // namespace

Status PassMetrics::init(Context& ctx, const char* passName, bool countsRays) {
  Context::Impl& c = internal::contextImpl(ctx);
  const uint32_t slots = c.desc.framesInFlight;
  name_ = passName;
  if (countsRays) {
    const VkDeviceSize bytes = VkDeviceSize(slots) * kCountersPerFrame * sizeof(uint32_t);
    Result<GpuBuffer> b = createBuffer(ctx, bytes,
                                       VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | VK_BUFFER_USAGE_TRANSFER_DST_BIT |
                                           VK_BUFFER_USAGE_TRANSFER_SRC_BIT,
                                       MemoryLocation::DeviceLocal, MemoryCategory::PassBuffers, passName);
    if (!b) return b.error();
    counters_ = b.value();
    Result<GpuBuffer> r = createBuffer(ctx, bytes, VK_BUFFER_USAGE_TRANSFER_DST_BIT, MemoryLocation::HostVisible,
                                       MemoryCategory::PassBuffers, passName);
    if (!r) {
      destroyBuffer(ctx, counters_);
      return r.error();
    }
    readback_ = r.value();
    std::memset(readback_.mapped, 0, readback_.size);
  }
  recordedFrame_.assign(slots, UINT64_MAX);
  hostRays_.assign(slots, 0);
  timing_ = c.info.timestampsSupported;
  if (timing_) {
    VkQueryPoolCreateInfo qi{VK_STRUCTURE_TYPE_QUERY_POOL_CREATE_INFO};
    qi.queryType = VK_QUERY_TYPE_TIMESTAMP;
    qi.queryCount = 2 * slots;
    VkQueryPool pool = VK_NULL_HANDLE;  // not the member: a failed create leaves its output undefined
    VkResult r = c.vk.vkCreateQueryPool(c.desc.device, &qi, c.allocator(), &pool);
    if (r != VK_SUCCESS) return vulkanError(r, std::string("vkCreateQueryPool for ") + passName);
    timestamps_ = pool;
  }
  return {};
}

void PassMetrics::retire(Context& ctx) {
  internal::contextImpl(ctx).retireHandle(timestamps_, &DeviceFunctions::vkDestroyQueryPool);
  retireBuffer(ctx, counters_);
  retireBuffer(ctx, readback_);
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
    s.rays = hostRays_[slot];
    if (readback_.valid()) {
      const uint32_t* counts = reinterpret_cast<const uint32_t*>(static_cast<const uint8_t*>(readback_.mapped) +
                                                                 slot * counterBytes());
      for (uint32_t i = 0; i < kCounterSlots; ++i) s.rays += counts[i];
      for (uint32_t i = 0; i < kCounterSlots; ++i) s.anyHitInvocations += counts[kCounterSlots + i];
      s.tilesTraced = counts[2 * kCounterSlots];  // RayCounters::tilesTraced, then tilesSkipped
      s.tilesSkipped = counts[2 * kCounterSlots + 1];
      s.tilesConverged = counts[2 * kCounterSlots + 2];  // then tilesConverged, raysSaved
      s.raysSaved = counts[2 * kCounterSlots + 3];
    }
    if (timing_) {
      uint64_t ticks[2] = {0, 0};
      const VkResult r = c.vk.vkGetQueryPoolResults(c.desc.device, timestamps_, 2 * slot, 2, sizeof ticks, ticks,
                                                    sizeof(uint64_t), VK_QUERY_RESULT_64_BIT);
      if (r == VK_SUCCESS) {
        s.gpuMs = double(c.info.timestampTicks(ticks[0], ticks[1])) * c.info.timestampPeriodNs * 1e-6;
      } else if (r != VK_NOT_READY && readError_) {
        readError_ = vulkanError(r, std::string("vkGetQueryPoolResults (") + name_ + " timestamps)");
      }
    }
    if (s.frame >= latest_.frame) latest_ = s;
    recordedFrame_[slot] = UINT64_MAX;
  }
}

Status PassMetrics::beginRecording(Context& ctx, VkCommandBuffer cmd) {
  collect(ctx);
  if (!readError_) return std::exchange(readError_, Status());
  Context::Impl& c = internal::contextImpl(ctx);
  const uint32_t slot = static_cast<uint32_t>(c.frame % c.desc.framesInFlight);
  recordedFrame_[slot] = c.frame;
  hostRays_[slot] = 0;
  if (timing_) c.vk.vkCmdResetQueryPool(cmd, timestamps_, 2 * slot, 2);
  if (!counters_.valid()) return {};
  // After any earlier use of the counters in this command buffer (the pass recorded twice in a frame): clear, then
  // let the shaders add.
  // TRANSFER_WRITE in the first scope: the earlier recording's fill and readback copy (write after write).
  recordMemoryBarrier(c.vk, cmd, kCounterShaderStages | VK_PIPELINE_STAGE_TRANSFER_BIT,
                      VK_ACCESS_SHADER_READ_BIT | VK_ACCESS_SHADER_WRITE_BIT | VK_ACCESS_TRANSFER_READ_BIT |
                          VK_ACCESS_TRANSFER_WRITE_BIT,
                      VK_PIPELINE_STAGE_TRANSFER_BIT, VK_ACCESS_TRANSFER_WRITE_BIT);
  c.vk.vkCmdFillBuffer(cmd, counters_.buffer, slot * counterBytes(), counterBytes(), 0u);
  recordMemoryBarrier(c.vk, cmd, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_ACCESS_TRANSFER_WRITE_BIT, kCounterShaderStages,
                      VK_ACCESS_SHADER_READ_BIT | VK_ACCESS_SHADER_WRITE_BIT);
  return {};
}

void PassMetrics::addHostRays(Context& ctx, uint64_t rays) {
  hostRays_[ctx.frameIndex() % ctx.framesInFlight()] += rays;
}

void PassMetrics::writeStart(Context& ctx, VkCommandBuffer cmd) {
  if (!timing_) return;
  const uint32_t slot = static_cast<uint32_t>(ctx.frameIndex() % ctx.framesInFlight());
  internal::deviceFunctions(ctx).vkCmdWriteTimestamp(cmd, VK_PIPELINE_STAGE_ALL_COMMANDS_BIT, timestamps_, 2 * slot);
}

void PassMetrics::writeEnd(Context& ctx, VkCommandBuffer cmd) {
  const DeviceFunctions& vk = internal::deviceFunctions(ctx);
  const uint32_t slot = static_cast<uint32_t>(ctx.frameIndex() % ctx.framesInFlight());
  if (timing_) vk.vkCmdWriteTimestamp(cmd, VK_PIPELINE_STAGE_ALL_COMMANDS_BIT, timestamps_, 2 * slot + 1);
  if (!counters_.valid()) return;
  recordMemoryBarrier(vk, cmd, kCounterShaderStages, VK_ACCESS_SHADER_WRITE_BIT, VK_PIPELINE_STAGE_TRANSFER_BIT,
                      VK_ACCESS_TRANSFER_READ_BIT);
  const VkBufferCopy region{slot * counterBytes(), slot * counterBytes(), counterBytes()};
  vk.vkCmdCopyBuffer(cmd, counters_.buffer, readback_.buffer, 1, &region);
  // The host reads the copy after the frame's fence (collect()).
  recordMemoryBarrier(vk, cmd, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_ACCESS_TRANSFER_WRITE_BIT, VK_PIPELINE_STAGE_HOST_BIT,
                      VK_ACCESS_HOST_READ_BIT);
}

}  // namespace rb
