// Context internals shared by the services and passes: the function table, device facts, memory
// accounting and the deferred-release queue.
#pragma once

#include <raybridge/context.h>

#include <functional>
#include <vector>

#include "context_access.h"
#include "device_functions.h"
#include "vulkan_errors.h"

namespace rb {

struct Context::Impl {
  ContextDesc desc{};
  DeviceFunctions vk{};
  DeviceInfo info{};
  VkPhysicalDeviceMemoryProperties memoryProperties{};
  uint64_t frame = 0;
  // Every frame up to this one is known to be done because the engine said the device was idle.
  uint64_t idleThrough = 0;
  bool idleSeen = false;
  MemoryStats memory{};
  // Memory attribution (HybridEffects::memoryByEffect): what is allocated while memoryOwner is set (MemoryOwnerScope)
  // counts to that owner too, until it is freed. Ids come from newMemoryOwner(), 0 is nobody's. A released id is given
  // out again once everything counted to it is freed (what its owner retired may outlive it by frames in flight), so
  // an engine that creates and destroys front ends every frame holds a bounded number of them.
  uint32_t memoryOwner = 0;
  std::vector<MemoryStats> ownerMemory;  // [id - 1]
  std::vector<uint32_t> releasedOwners;
  uint32_t newMemoryOwner() {
    for (auto it = releasedOwners.begin(); it != releasedOwners.end(); ++it) {
      const uint32_t id = *it;
      if (ownerMemory[id - 1].allocations != 0) continue;
      releasedOwners.erase(it);
      return id;
    }
    ownerMemory.emplace_back();
    return uint32_t(ownerMemory.size());
  }
  void releaseMemoryOwner(uint32_t id) {
    if (id != 0) releasedOwners.push_back(id);
  }

  struct PendingRelease {
    uint64_t frame;  // frame in which it was retired
    std::function<void()> release;
  };
  std::vector<PendingRelease> pendingReleases;

  // Runs `release` once no frame that may have used the object is in flight any more: at the beginFrame()
  // framesInFlight frames after this one, at releaseAfterIdle(), or at ~Context. This is how every SDK object
  // that a recorded command buffer may reference is destroyed, so the memory statistics drop when the memory
  // is actually freed.
  void retire(std::function<void()> release) { pendingReleases.push_back({frame, std::move(release)}); }
  // retire() for a plain handle destroyed by one device function, e.g.
  //   c.retireHandle(sampler, &DeviceFunctions::vkDestroySampler);
  // `handle` is left VK_NULL_HANDLE.
  template <typename Handle, typename DestroyFn>
  void retireHandle(Handle& handle, DestroyFn DeviceFunctions::*destroy) {
    if (handle == VK_NULL_HANDLE) return;
    Handle retired = handle;
    handle = VK_NULL_HANDLE;
    retire([this, retired, destroy] { (vk.*destroy)(desc.device, retired, allocator()); });
  }
  void releaseRetired(bool deviceIdle);
  // True once the GPU has finished the work recorded in `recordedFrame` (beginFrame contract or idle).
  bool frameDone(uint64_t recordedFrame) const {
    return recordedFrame + desc.framesInFlight <= frame || (idleSeen && recordedFrame <= idleThrough);
  }
  int32_t findMemoryType(uint32_t typeBits, VkMemoryPropertyFlags required, VkMemoryPropertyFlags preferred) const;
  const VkAllocationCallbacks* allocator() const { return desc.allocationCallbacks; }

  // Signals that hold kept-history marks this frame: a pass that skipped converged tiles wrote them into its output
  // (converged_tiles.cpp), and the Denoiser that filters that view reads them as "no new frame"
  // (RB_DN_KEPT_MARKS). Keyed by the view, not by a denoiser, so no object reaches into another.
  void markKeptHistory(VkImageView signal) {
    std::erase_if(keptMarkSignals, [&](const KeptMarks& k) { return k.frame != frame || k.signal == signal; });
    keptMarkSignals.push_back({signal, frame});
  }
  bool holdsKeptMarks(VkImageView signal) const {
    for (const KeptMarks& k : keptMarkSignals) {
      if (k.signal == signal && k.frame == frame) return true;
    }
    return false;
  }
  struct KeptMarks {
    VkImageView signal;
    uint64_t frame;
  };
  std::vector<KeptMarks> keptMarkSignals;
};

// Attributes what is allocated during its lifetime to `owner` (Context::Impl::memoryOwner); restores the previous
// owner after, so that scopes nest (an effect's scope inside HybridEffects' own).
class MemoryOwnerScope {
 public:
  MemoryOwnerScope(Context::Impl& c, uint32_t owner) : c_(c), previous_(c.memoryOwner) { c.memoryOwner = owner; }
  ~MemoryOwnerScope() { c_.memoryOwner = previous_; }
  MemoryOwnerScope(const MemoryOwnerScope&) = delete;
  MemoryOwnerScope& operator=(const MemoryOwnerScope&) = delete;

 private:
  Context::Impl& c_;
  uint32_t previous_;
};

}  // namespace rb
