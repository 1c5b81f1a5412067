#include "gpu_timer.h"

#include <string>

namespace rbbench {

GpuTimer::GpuTimer(BenchEnv& env, uint32_t capacity) : env_(env), capacity_(capacity) {
  VkQueryPoolCreateInfo qi{VK_STRUCTURE_TYPE_QUERY_POOL_CREATE_INFO};
  qi.queryType = VK_QUERY_TYPE_TIMESTAMP;
  qi.queryCount = capacity;
  VkResult r = env.vk().vkCreateQueryPool(env.device().device(), &qi, nullptr, &pool_);
  if (r != VK_SUCCESS) throw BenchFailure("vkCreateQueryPool for the bench timer failed: " + std::to_string(r));
}

GpuTimer::~GpuTimer() {
  if (pool_) env_.vk().vkDestroyQueryPool(env_.device().device(), pool_, nullptr);
}

void GpuTimer::reset(VkCommandBuffer cmd) {
  env_.vk().vkCmdResetQueryPool(cmd, pool_, 0, capacity_);
  used_ = 0;
  ticks_.clear();
}

uint32_t GpuTimer::mark(VkCommandBuffer cmd) {
  if (used_ >= capacity_) throw BenchFailure("GpuTimer: more marks than the pool's " + std::to_string(capacity_));
  env_.vk().vkCmdWriteTimestamp(cmd, VK_PIPELINE_STAGE_ALL_COMMANDS_BIT, pool_, used_);
  return used_++;
}

void GpuTimer::resolve() {
  ticks_.assign(used_, 0);
  if (used_ == 0) return;
  VkResult r = env_.vk().vkGetQueryPoolResults(env_.device().device(), pool_, 0, used_, used_ * sizeof(uint64_t),
                                               ticks_.data(), sizeof(uint64_t),
                                               VK_QUERY_RESULT_64_BIT | VK_QUERY_RESULT_WAIT_BIT);
  if (r != VK_SUCCESS) throw BenchFailure("vkGetQueryPoolResults for the bench timer failed: " + std::to_string(r));
}

double GpuTimer::ms(uint32_t from, uint32_t to) const {
  if (from >= ticks_.size() || to >= ticks_.size()) throw BenchFailure("GpuTimer: mark not resolved");
  const uint32_t bits = env_.timestampValidBits();
  const uint64_t mask = bits >= 64 ? ~0ull : ((1ull << bits) - 1);
  const uint64_t delta = (ticks_[to] - ticks_[from]) & mask;
  return double(delta) * env_.info().timestampPeriodNs * 1e-6;
}

}  // namespace rbbench
