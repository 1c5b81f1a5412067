#include "frame_ring.h"

#include <string>

namespace rbbench {

namespace {

void checkVk(VkResult r, const char* what) {
  if (r != VK_SUCCESS) throw BenchFailure(std::string(what) + " failed: VkResult " + std::to_string(r));
}

}  // namespace

FrameRing::FrameRing(BenchEnv& env) : env_(env) {
  rb::HeadlessDevice& dev = env.device();
  createFence_ = reinterpret_cast<PFN_vkCreateFence>(dev.deviceProc("vkCreateFence"));
  destroyFence_ = reinterpret_cast<PFN_vkDestroyFence>(dev.deviceProc("vkDestroyFence"));
  waitForFences_ = reinterpret_cast<PFN_vkWaitForFences>(dev.deviceProc("vkWaitForFences"));
  resetFences_ = reinterpret_cast<PFN_vkResetFences>(dev.deviceProc("vkResetFences"));
  if (!createFence_ || !destroyFence_ || !waitForFences_ || !resetFences_) {
    throw BenchFailure("the device exposes no fence functions");
  }
  const uint32_t frames = env.ctx().framesInFlight();
  VkCommandPoolCreateInfo pci{VK_STRUCTURE_TYPE_COMMAND_POOL_CREATE_INFO};
  pci.flags = VK_COMMAND_POOL_CREATE_RESET_COMMAND_BUFFER_BIT;
  pci.queueFamilyIndex = dev.queueFamily();
  checkVk(env.vk().vkCreateCommandPool(dev.device(), &pci, nullptr, &pool_), "vkCreateCommandPool (frame ring)");
  commands_.resize(frames);
  VkCommandBufferAllocateInfo ai{VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO};
  ai.commandPool = pool_;
  ai.level = VK_COMMAND_BUFFER_LEVEL_PRIMARY;
  ai.commandBufferCount = frames;
  checkVk(env.vk().vkAllocateCommandBuffers(dev.device(), &ai, commands_.data()), "vkAllocateCommandBuffers");
  fences_.resize(frames, VK_NULL_HANDLE);
  submitted_.resize(frames, false);
  for (VkFence& f : fences_) {
    VkFenceCreateInfo fci{VK_STRUCTURE_TYPE_FENCE_CREATE_INFO};
    checkVk(createFence_(dev.device(), &fci, nullptr, &f), "vkCreateFence (frame ring)");
  }
}

FrameRing::~FrameRing() {
  VkDevice device = env_.device().device();
  try {
    waitAll();
  } catch (const BenchFailure&) {
    (void)env_.device().waitIdle();  // a lost device: nothing better to do in a destructor
  }
  for (VkFence f : fences_) destroyFence_(device, f, nullptr);
  if (pool_) env_.vk().vkDestroyCommandPool(device, pool_, nullptr);
}

VkCommandBuffer FrameRing::begin() {
  slot_ = first_ ? 0 : (slot_ + 1) % uint32_t(commands_.size());
  first_ = false;
  VkDevice device = env_.device().device();
  if (submitted_[slot_]) {
    checkVk(waitForFences_(device, 1, &fences_[slot_], VK_TRUE, UINT64_MAX), "vkWaitForFences (frame slot)");
    checkVk(resetFences_(device, 1, &fences_[slot_]), "vkResetFences");
    submitted_[slot_] = false;
  }
  // The GPU is done with what this slot submitted framesInFlight frames ago: Context::beginFrame's contract.
  env_.ctx().beginFrame();
  VkCommandBuffer cmd = commands_[slot_];
  checkVk(env_.vk().vkResetCommandBuffer(cmd, 0), "vkResetCommandBuffer");
  VkCommandBufferBeginInfo bi{VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO};
  bi.flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT;
  checkVk(env_.vk().vkBeginCommandBuffer(cmd, &bi), "vkBeginCommandBuffer");
  return cmd;
}

void FrameRing::submit() {
  VkCommandBuffer cmd = commands_[slot_];
  checkVk(env_.vk().vkEndCommandBuffer(cmd), "vkEndCommandBuffer");
  VkSubmitInfo si{VK_STRUCTURE_TYPE_SUBMIT_INFO};
  si.commandBufferCount = 1;
  si.pCommandBuffers = &cmd;
  checkVk(env_.vk().vkQueueSubmit(env_.device().queue(), 1, &si, fences_[slot_]), "vkQueueSubmit (frame)");
  submitted_[slot_] = true;
}

void FrameRing::waitAll() {
  VkDevice device = env_.device().device();
  for (size_t i = 0; i < fences_.size(); ++i) {
    if (!submitted_[i]) continue;
    checkVk(waitForFences_(device, 1, &fences_[i], VK_TRUE, UINT64_MAX), "vkWaitForFences (all frames)");
    checkVk(resetFences_(device, 1, &fences_[i]), "vkResetFences");
    submitted_[i] = false;
  }
}

}  // namespace rbbench
