// The SDK's own submissions on the compute queue the engine hands over (AsServiceDesc::asyncQueue): a small ring
// of command buffers and one timeline semaphore that every submission signals, so the engine can wait for it and
// the SDK knows, without blocking, which submissions are done.
#pragma once

#include <raybridge/acceleration_structures.h>

#include <vector>

#include "context_impl.h"

namespace rb {

class AsyncSubmitter {
 public:
  Status create(Context::Impl& c, VkQueue queue, uint32_t family);
  // Destroys everything. Contract: every submission is done (the engine's wait-idle, or its wait on semaphore()).
  void destroy();
  bool active() const { return semaphore_ != VK_NULL_HANDLE; }

  // A command buffer in the recording state: one whose submission the timeline shows finished (checked without
  // blocking), else a newly allocated one. Fails naming the call when the timeline cannot be read (a lost device).
  Result<VkCommandBuffer> begin();
  // Ends `cmd` and submits it waiting on `ready` (stages `readyStages`), signalling the next timeline value,
  // which it returns.
  Result<uint64_t> submit(VkCommandBuffer cmd, const AsyncBuildWait& ready, VkPipelineStageFlags readyStages);
  // Ends a command buffer begin() gave out that will not be submitted, and makes it reusable.
  void abandon(VkCommandBuffer cmd);

  // The timeline's current value (non-blocking); where reading it fails (a lost device), the value read last.
  // begin() reports such a failure.
  uint64_t completedValue() const;
  uint64_t lastSubmitted() const { return lastValue_; }
  VkSemaphore semaphore() const { return semaphore_; }
  uint32_t family() const { return family_; }

 private:
  struct Slot {
    VkCommandBuffer cmd = VK_NULL_HANDLE;
    uint64_t value = 0;  // timeline value of its last submission; 0 = never submitted
    bool recording = false;
  };
  Context::Impl* c_ = nullptr;
  VkQueue queue_ = VK_NULL_HANDLE;
  uint32_t family_ = UINT32_MAX;
  VkCommandPool pool_ = VK_NULL_HANDLE;
  VkSemaphore semaphore_ = VK_NULL_HANDLE;
  uint64_t lastValue_ = 0;
  mutable uint64_t completed_ = 0;  // the timeline's value read last
  std::vector<Slot> slots_;
};

}  // namespace rb
