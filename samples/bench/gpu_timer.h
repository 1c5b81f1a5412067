// Timestamp queries of the bench's own (the service times its BLAS build batches itself): a pool reset at the
// start of a command buffer, marks written in order, read back after the submission has completed.
#pragma once

#include <cstdint>
#include <vector>

#include "bench_env.h"

namespace rbbench {

class GpuTimer {
 public:
  GpuTimer(BenchEnv& env, uint32_t capacity);
  ~GpuTimer();
  GpuTimer(const GpuTimer&) = delete;
  GpuTimer& operator=(const GpuTimer&) = delete;

  // Resets every query and the mark counter; record before the first mark of a command buffer.
  void reset(VkCommandBuffer cmd);
  // Writes a timestamp once all earlier commands are complete; returns its index.
  uint32_t mark(VkCommandBuffer cmd);
  // After the command buffer completed: reads the marks written since reset().
  void resolve();
  // Milliseconds between two marks.
  double ms(uint32_t from, uint32_t to) const;

 private:
  BenchEnv& env_;
  VkQueryPool pool_ = VK_NULL_HANDLE;
  uint32_t capacity_ = 0;
  uint32_t used_ = 0;
  std::vector<uint64_t> ticks_;
};

}  // namespace rbbench
