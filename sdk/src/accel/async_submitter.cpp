#include "async_submitter.h"

namespace rb {

Status AsyncSubmitter::create(Context::Impl& c, VkQueue queue, uint32_t family) {
  c_ = &c;
  queue_ = queue;
  family_ = family;
  // Created into locals: a failed create leaves its output undefined, and destroy() destroys the members.
  VkCommandPoolCreateInfo pi{VK_STRUCTURE_TYPE_COMMAND_POOL_CREATE_INFO};
  pi.flags = VK_COMMAND_POOL_CREATE_RESET_COMMAND_BUFFER_BIT;
  pi.queueFamilyIndex = family;
  VkCommandPool pool = VK_NULL_HANDLE;
  VkResult r = c.vk.vkCreateCommandPool(c.desc.device, &pi, c.allocator(), &pool);
  if (r != VK_SUCCESS) return vulkanError(r, "vkCreateCommandPool (async BLAS builds)");
  pool_ = pool;
  VkSemaphoreTypeCreateInfo type{VK_STRUCTURE_TYPE_SEMAPHORE_TYPE_CREATE_INFO};
  type.semaphoreType = VK_SEMAPHORE_TYPE_TIMELINE;
  type.initialValue = 0;
  VkSemaphoreCreateInfo si{VK_STRUCTURE_TYPE_SEMAPHORE_CREATE_INFO, &type};
  VkSemaphore semaphore = VK_NULL_HANDLE;
  r = c.vk.vkCreateSemaphore(c.desc.device, &si, c.allocator(), &semaphore);
  if (r != VK_SUCCESS) {
    destroy();
    return vulkanError(r, "vkCreateSemaphore (async BLAS timeline; is the timelineSemaphore feature enabled?)");
  }
  semaphore_ = semaphore;
  return {};
}

void AsyncSubmitter::destroy() {
  if (!c_) return;
  // Contract (~AccelerationStructureService): the GPU is done, the async queue included; the SDK never waits.
  Context::Impl& c = *c_;
  if (pool_) c.vk.vkDestroyCommandPool(c.desc.device, pool_, c.allocator());  // frees the command buffers
  if (semaphore_) c.vk.vkDestroySemaphore(c.desc.device, semaphore_, c.allocator());
  pool_ = VK_NULL_HANDLE;
  semaphore_ = VK_NULL_HANDLE;
  slots_.clear();
}

uint64_t AsyncSubmitter::completedValue() const {
  uint64_t value = 0;
  // On an error (a lost device) the value read last: nothing counts as done that was not seen done.
  if (semaphore_ && c_->vk.vkGetSemaphoreCounterValue(c_->desc.device, semaphore_, &value) == VK_SUCCESS) {
    completed_ = value;
  }
  return completed_;
}

Result<VkCommandBuffer> AsyncSubmitter::begin() {
  Context::Impl& c = *c_;
  uint64_t done = 0;
  if (VkResult r = c.vk.vkGetSemaphoreCounterValue(c.desc.device, semaphore_, &done); r != VK_SUCCESS) {
    return vulkanError(r, "vkGetSemaphoreCounterValue (async BLAS timeline)");
  }
  completed_ = done;
  Slot* slot = nullptr;
  for (Slot& s : slots_) {
    if (!s.recording && s.value <= done) {
      slot = &s;
      break;
    }
  }
  if (!slot) {
    VkCommandBufferAllocateInfo ai{VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO};
    ai.commandPool = pool_;
    ai.level = VK_COMMAND_BUFFER_LEVEL_PRIMARY;
    ai.commandBufferCount = 1;
    Slot s;
    VkResult r = c.vk.vkAllocateCommandBuffers(c.desc.device, &ai, &s.cmd);
    if (r != VK_SUCCESS) return vulkanError(r, "vkAllocateCommandBuffers (async BLAS builds)");
    slots_.push_back(s);
    slot = &slots_.back();
  } else {
    VkResult r = c.vk.vkResetCommandBuffer(slot->cmd, 0);
    if (r != VK_SUCCESS) return vulkanError(r, "vkResetCommandBuffer (async BLAS builds)");
  }
  VkCommandBufferBeginInfo bi{VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO};
  bi.flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT;
  VkResult r = c.vk.vkBeginCommandBuffer(slot->cmd, &bi);
  if (r != VK_SUCCESS) return vulkanError(r, "vkBeginCommandBuffer (async BLAS builds)");
  slot->recording = true;
  return slot->cmd;
}

void AsyncSubmitter::abandon(VkCommandBuffer cmd) {
  for (Slot& s : slots_) {
    if (s.cmd != cmd) continue;
    (void)c_->vk.vkEndCommandBuffer(cmd);
    s.recording = false;
  }
}

Result<uint64_t> AsyncSubmitter::submit(VkCommandBuffer cmd, const AsyncBuildWait& ready,
                                        VkPipelineStageFlags readyStages) {
  Context::Impl& c = *c_;
  Slot* slot = nullptr;
  for (Slot& s : slots_) slot = s.cmd == cmd ? &s : slot;
  if (!slot) return Error{ErrorCode::InvalidArgument, VK_SUCCESS, "internal: unknown async command buffer"};
  slot->recording = false;
  VkResult r = c.vk.vkEndCommandBuffer(cmd);
  if (r != VK_SUCCESS) return vulkanError(r, "vkEndCommandBuffer (async BLAS builds)");
  const uint64_t signal = lastValue_ + 1;
  const bool wait = ready.semaphore != VK_NULL_HANDLE;
  VkTimelineSemaphoreSubmitInfo timeline{VK_STRUCTURE_TYPE_TIMELINE_SEMAPHORE_SUBMIT_INFO};
  timeline.waitSemaphoreValueCount = wait ? 1 : 0;
  timeline.pWaitSemaphoreValues = &ready.value;
  timeline.signalSemaphoreValueCount = 1;
  timeline.pSignalSemaphoreValues = &signal;
  VkSubmitInfo si{VK_STRUCTURE_TYPE_SUBMIT_INFO, &timeline};
  si.waitSemaphoreCount = wait ? 1 : 0;
  si.pWaitSemaphores = &ready.semaphore;
  si.pWaitDstStageMask = &readyStages;
  si.commandBufferCount = 1;
  si.pCommandBuffers = &cmd;
  si.signalSemaphoreCount = 1;
  si.pSignalSemaphores = &semaphore_;
  r = c.vk.vkQueueSubmit(queue_, 1, &si, VK_NULL_HANDLE);
  if (r != VK_SUCCESS) return vulkanError(r, "vkQueueSubmit (async BLAS builds)");
  lastValue_ = signal;
  slot->value = signal;
  return signal;
}

}  // namespace rb
