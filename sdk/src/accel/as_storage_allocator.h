// Packs acceleration-structure storage into large device buffers at the required 256-byte alignment instead
// of one buffer (and one VkDeviceMemory) per BLAS. The blocks grow with the content: the first is
// kMinBlockBytes, each new one as large as those held together (so the blocks' count grows with the log of the
// content), at most the block size given (AsServiceDesc::storageBlockBytes); a BLAS larger than that gets a block
// of its own size. An empty block is released at once, so the memory held comes back down with the content.
#pragma once

#include <vector>

#include "gpu_memory.h"

namespace rb {

struct StorageAllocation {
  uint32_t block = UINT32_MAX;
  VkDeviceSize offset = 0;
  VkDeviceSize size = 0;  // aligned size held
  bool valid() const { return block != UINT32_MAX; }
};

class AsStorageAllocator {
 public:
  static constexpr VkDeviceSize kAlignment = 256;  // VkAccelerationStructureCreateInfoKHR::offset rule
  // The first block's size: a scene of a few thousand triangles reserves about this much.
  static constexpr VkDeviceSize kMinBlockBytes = 256ull << 10;

  // `maxBlockBytes`: the largest block grown to. `sharedWith`: the queue families whose queues build or read these
  // BLASes when there are two (the blocks are then VK_SHARING_MODE_CONCURRENT over them); empty = the main queue
  // only.
  AsStorageAllocator(Context& ctx, VkDeviceSize maxBlockBytes, std::vector<uint32_t> sharedWith = {})
      : ctx_(ctx), maxBlockBytes_(maxBlockBytes), sharedWith_(std::move(sharedWith)) {}
  ~AsStorageAllocator();

  Result<StorageAllocation> allocate(VkDeviceSize size);
  // Returns the range at once: call it when no frame in flight can use the range any more.
  void free(const StorageAllocation& allocation);
  VkBuffer buffer(uint32_t block) const { return blocks_[block].buffer.buffer; }

  uint32_t blockCount() const;
  VkDeviceSize blockBytes() const;  // device memory held
  VkDeviceSize usedBytes() const;

 private:
  struct Range {
    VkDeviceSize offset, size;
  };
  struct Block {
    GpuBuffer buffer;
    std::vector<Range> freeRanges;  // sorted by offset, coalesced
    VkDeviceSize used = 0;
  };
  Context& ctx_;
  VkDeviceSize maxBlockBytes_;
  std::vector<uint32_t> sharedWith_;
  std::vector<Block> blocks_;  // a destroyed block keeps its slot (invalid buffer) so indices stay stable
};

}  // namespace rb
