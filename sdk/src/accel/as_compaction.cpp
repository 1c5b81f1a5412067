// Build queries and compaction of the acceleration-structure service: reads the timings and compacted sizes of
// finished build batches, and records the compaction copies that replace BLAS storage by a smaller copy.
#include <raybridge/acceleration_structures.h>

#include <string>
#include <utility>
#include <vector>

#include "as_service_impl.h"

namespace rb {

namespace {

// A compacted size that saves less than this share of the built size is not worth the copy (lavapipe reports the
// built size itself: every compaction there would copy for nothing).
constexpr VkDeviceSize kMinCompactionSavingPercent = 2;

}  // namespace

void AccelerationStructureService::Impl::addTiming(const BuildBatchTiming& timing) {
  timings.push_back(timing);
  if (timings.size() > kMaxBatchTimings) {
    timings.erase(timings.begin());
    ++counters.batchTimingsDropped;
  }
}

void AccelerationStructureService::Impl::resolveBatches() {
  auto failed = [&](VkResult r, const char* what) {
    if (queryError) queryError = vulkanError(r, std::string("vkGetQueryPoolResults (") + what + ")");
  };
  std::vector<BuildBatch> keep;
  for (BuildBatch& b : inFlightBatches) {
    if (!c.frameDone(b.frame)) {
      keep.push_back(b);
      continue;
    }
    if (b.timestamps) {
      uint64_t ticks[2] = {0, 0};
      VkResult r = c.vk.vkGetQueryPoolResults(c.desc.device, b.timestamps, 0, 2, sizeof(ticks), ticks, sizeof(uint64_t),
                                              VK_QUERY_RESULT_64_BIT);
      if (r == VK_NOT_READY) {
        keep.push_back(b);
        continue;
      }
      if (r == VK_SUCCESS) {
        addTiming({b.frame, b.builds, b.triangles,
                   double(c.info.timestampTicks(ticks[0], ticks[1])) * c.info.timestampPeriodNs * 1e-6});
      } else {
        failed(r, "BLAS build timestamps");  // a lost device: the batch goes without a timing
      }
      freeTimestampPools.push_back(b.timestamps);
    }
    if (b.compactedSizes) {
      std::vector<uint64_t> sizes(b.compactEntries.size(), 0);
      VkResult r = c.vk.vkGetQueryPoolResults(c.desc.device, b.compactedSizes, 0, static_cast<uint32_t>(sizes.size()),
                                              sizes.size() * sizeof(uint64_t), sizes.data(), sizeof(uint64_t),
                                              VK_QUERY_RESULT_64_BIT);
      if (r == VK_SUCCESS) {
        for (size_t i = 0; i < sizes.size(); ++i) {
          BlasEntry& e = entries[b.compactEntries[i]];
          if (e.generation != b.compactGenerations[i] || e.state != BlasState::Built || !e.compactionPending) continue;
          e.compactionPending = false;
          // Lavapipe reports the built size: a copy would cost time and save nothing.
          if (sizes[i] == 0 || sizes[i] * 100 >= e.builtSize * (100 - kMinCompactionSavingPercent)) {
            ++counters.compactionsSkipped;
          } else {
            e.compactedSize = sizes[i];
          }
        }
      } else {
        failed(r, "BLAS compacted sizes");  // the BLASes stay uncompacted
      }
      c.vk.vkDestroyQueryPool(c.desc.device, b.compactedSizes, c.allocator());
    }
  }
  inFlightBatches = std::move(keep);
}

Status AccelerationStructureService::Impl::recordCompactions(VkCommandBuffer cmd, bool& recordedAny) {
  bool copied = false;
  Status status;  // a failed copy stays queued for the next call; the copies recorded before it still count
  for (uint32_t i = 1; i < entries.size(); ++i) {
    BlasEntry& e = entries[i];
    if (e.state != BlasState::Built || e.compactedSize == 0 || e.compacted) continue;
    Result<StorageAllocation> alloc = storage.allocate(e.compactedSize);
    if (!alloc) {
      status = alloc.error();
      break;
    }
    Result<VkAccelerationStructureKHR> as = createAs(VK_ACCELERATION_STRUCTURE_TYPE_BOTTOM_LEVEL_KHR,
                                                     storage.buffer(alloc->block), alloc->offset, e.compactedSize);
    if (!as) {
      storage.free(alloc.value());
      status = as.error();
      break;
    }
    VkCopyAccelerationStructureInfoKHR copy{VK_STRUCTURE_TYPE_COPY_ACCELERATION_STRUCTURE_INFO_KHR};
    copy.src = e.as;
    copy.dst = as.value();
    copy.mode = VK_COPY_ACCELERATION_STRUCTURE_MODE_COMPACT_KHR;
    c.vk.vkCmdCopyAccelerationStructureKHR(cmd, &copy);
    VkAccelerationStructureKHR old = e.as;
    StorageAllocation oldAlloc = e.storage;
    c.retire([this, old, oldAlloc] {
      c.vk.vkDestroyAccelerationStructureKHR(c.desc.device, old, c.allocator());
      storage.free(oldAlloc);
    });
    reservedBytes -= e.reserved;
    e.reserved = alloc->size;
    reservedBytes += e.reserved;
    e.as = as.value();
    e.storage = alloc.value();
    e.currentSize = e.compactedSize;
    VkAccelerationStructureDeviceAddressInfoKHR ai{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_DEVICE_ADDRESS_INFO_KHR};
    ai.accelerationStructure = e.as;
    e.address = c.vk.vkGetAccelerationStructureDeviceAddressKHR(c.desc.device, &ai);
    e.compacted = true;
    ++counters.blasCompacted;
    copied = true;
  }
  if (copied) {
    recordedAny = true;
    recordAsBarrier(c.vk, cmd, VK_PIPELINE_STAGE_ACCELERATION_STRUCTURE_BUILD_BIT_KHR);
  }
  return status;
}

}  // namespace rb
