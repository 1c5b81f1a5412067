// Frames in flight the way an engine runs them, for scenarios that must not wait for each frame (BenchEnv::runFrame
// does): one command buffer and fence per frame slot, the slot's fence waited for before Context::beginFrame, so
// the CPU records frame N while the GPU may still run frames N-1 .. N-F+1 and the Context's deferred releases
// happen as they would in an engine.
//
// Thread safety: drives the BenchEnv's queue; use it from the thread that drives the BenchEnv.
#pragma once

#include <vector>

#include "bench_env.h"

namespace rbbench {

class FrameRing {
 public:
  // One slot per frame in flight of the env's Context.
  explicit FrameRing(BenchEnv& env);
  ~FrameRing();  // waits for every slot, then frees the command buffers and fences
  FrameRing(const FrameRing&) = delete;
  FrameRing& operator=(const FrameRing&) = delete;

  // Waits for the submission that last used the next slot, calls Context::beginFrame and returns the slot's command
  // buffer, reset and begun.
  VkCommandBuffer begin();
  // Ends the command buffer begun last and submits it with the slot's fence; does not wait.
  void submit();
  // Waits until every submitted frame has finished (the fences; the queue may hold other work).
  void waitAll();
  uint32_t slot() const { return slot_; }

 private:
  BenchEnv& env_;
  VkCommandPool pool_ = VK_NULL_HANDLE;
  std::vector<VkCommandBuffer> commands_;
  std::vector<VkFence> fences_;
  std::vector<bool> submitted_;  // per slot: its fence will be signalled
  uint32_t slot_ = 0;
  bool first_ = true;
  PFN_vkCreateFence createFence_ = nullptr;
  PFN_vkDestroyFence destroyFence_ = nullptr;
  PFN_vkWaitForFences waitForFences_ = nullptr;
  PFN_vkResetFences resetFences_ = nullptr;
};

}  // namespace rbbench
