#include "as_storage_allocator.h"

#include <algorithm>

#include "align_up.h"

namespace rb {

AsStorageAllocator::~AsStorageAllocator() {
  for (Block& b : blocks_) destroyBuffer(ctx_, b.buffer);
}

Result<StorageAllocation> AsStorageAllocator::allocate(VkDeviceSize size) {
  VkDeviceSize need = alignUp(size, kAlignment);
  // First fit over existing blocks: BLASes are allocated in bursts at load time, so first fit keeps the
  // blocks dense without the bookkeeping of best fit.
  for (uint32_t bi = 0; bi < blocks_.size(); ++bi) {
    Block& b = blocks_[bi];
    if (!b.buffer.valid()) continue;
    for (size_t ri = 0; ri < b.freeRanges.size(); ++ri) {
      Range& r = b.freeRanges[ri];
      if (r.size < need) continue;
      StorageAllocation a{bi, r.offset, need};
      r.offset += need;
      r.size -= need;
      if (r.size == 0) b.freeRanges.erase(b.freeRanges.begin() + static_cast<ptrdiff_t>(ri));
      b.used += need;
      return a;
    }
  }
  // A new block doubles what is held (from kMinBlockBytes, up to maxBlockBytes_), and holds `need` whatever it is.
  const VkDeviceSize grown = std::clamp(blockBytes(), std::min(kMinBlockBytes, maxBlockBytes_), maxBlockBytes_);
  const VkDeviceSize bytes = std::max(grown, need);
  Result<GpuBuffer> buffer = createBuffer(
      ctx_, bytes, VK_BUFFER_USAGE_ACCELERATION_STRUCTURE_STORAGE_BIT_KHR | VK_BUFFER_USAGE_SHADER_DEVICE_ADDRESS_BIT,
      MemoryLocation::DeviceLocal, MemoryCategory::BlasStorage, "BLAS storage block", sharedWith_);
  if (!buffer) return buffer.error();
  Block block;
  block.buffer = buffer.value();
  block.used = need;
  if (bytes > need) block.freeRanges.push_back({need, bytes - need});
  uint32_t index = static_cast<uint32_t>(blocks_.size());
  for (uint32_t i = 0; i < blocks_.size(); ++i) {
    if (!blocks_[i].buffer.valid()) {
      index = i;
      break;
    }
  }
  if (index == blocks_.size()) {
    blocks_.push_back(std::move(block));
  } else {
    blocks_[index] = std::move(block);
  }
  return StorageAllocation{index, 0, need};
}

void AsStorageAllocator::free(const StorageAllocation& a) {
  if (!a.valid() || a.block >= blocks_.size()) return;
  Block& b = blocks_[a.block];
  auto it = std::lower_bound(b.freeRanges.begin(), b.freeRanges.end(), a.offset,
                             [](const Range& r, VkDeviceSize off) { return r.offset < off; });
  it = b.freeRanges.insert(it, {a.offset, a.size});
  // Coalesce with the neighbours so a freed block returns to a single range.
  if (it + 1 != b.freeRanges.end() && it->offset + it->size == (it + 1)->offset) {
    it->size += (it + 1)->size;
    b.freeRanges.erase(it + 1);
  }
  if (it != b.freeRanges.begin() && (it - 1)->offset + (it - 1)->size == it->offset) {
    (it - 1)->size += it->size;
    b.freeRanges.erase(it);
  }
  b.used -= a.size;
  if (b.used == 0) {
    destroyBuffer(ctx_, b.buffer);
    b.freeRanges.clear();
  }
}

uint32_t AsStorageAllocator::blockCount() const {
  return static_cast<uint32_t>(
      std::count_if(blocks_.begin(), blocks_.end(), [](const Block& b) { return b.buffer.valid(); }));
}

VkDeviceSize AsStorageAllocator::blockBytes() const {
  VkDeviceSize sum = 0;
  for (const Block& b : blocks_) sum += b.buffer.valid() ? b.buffer.size : 0;
  return sum;
}

VkDeviceSize AsStorageAllocator::usedBytes() const {
  VkDeviceSize sum = 0;
  for (const Block& b : blocks_) sum += b.used;
  return sum;
}

}  // namespace rb
