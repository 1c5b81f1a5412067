// Dynamic BLASes, the service side: where their work runs (in-frame or the async queue, with its fallback),
// their multi-buffered copies and lifetimes, updateMesh, and the waits the engine's submissions need.
#include <raybridge/acceleration_structures.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <utility>
#include <vector>

#include "as_service_impl.h"

namespace rb {

namespace {

std::string describe(const ValidatedMesh& m, uint32_t index) {
  return !m.debugName.empty() ? "mesh '" + m.debugName + "'" : "mesh #" + std::to_string(index);
}

const char* modeName(DynamicBuildMode m) {
  return m == DynamicBuildMode::AsyncSameFrame ? "DynamicBuildMode::AsyncSameFrame"
                                               : "DynamicBuildMode::AsyncOneFrameLate";
}

}  // namespace

Status AccelerationStructureService::Impl::initDynamic(const AsServiceDesc& d) {
  auto invalid = [](const std::string& m) { return Error{ErrorCode::InvalidArgument, VK_SUCCESS, m}; };
  if (d.dynamicMode > DynamicBuildMode::AsyncOneFrameLate) {
    return invalid("AsServiceDesc::dynamicMode " + std::to_string(static_cast<int>(d.dynamicMode)) +
                   " is not a DynamicBuildMode");
  }
  policy = d.refitPolicy;
  if (policy.kind > RefitPolicyKind::AlwaysRebuild) {
    return invalid("AsServiceDesc::refitPolicy.kind " + std::to_string(static_cast<int>(policy.kind)) +
                   " is not a RefitPolicyKind");
  }
  if (policy.maxAreaGrowth == 0.0f) policy.maxAreaGrowth = kDefaultMaxAreaGrowth;
  if (!(policy.maxAreaGrowth > 1.0f) || !std::isfinite(policy.maxAreaGrowth)) {
    return invalid("AsServiceDesc::refitPolicy.maxAreaGrowth is " + std::to_string(policy.maxAreaGrowth) +
                   "; use a growth ratio > 1 (0 = " + std::to_string(kDefaultMaxAreaGrowth) + ")");
  }
  if (policy.maxRefitsBeforeRebuild == 0) policy.maxRefitsBeforeRebuild = kDefaultMaxRefitsBeforeRebuild;
  if (policy.rebuildTrianglesPerFrame == 0) policy.rebuildTrianglesPerFrame = kDefaultRebuildTrianglesPerFrame;

  const uint32_t frames = c.desc.framesInFlight;
  std::string reason;
  if (d.dynamicMode != DynamicBuildMode::InFrame) {
    uint32_t familyCount = 0;
    c.vk.vkGetPhysicalDeviceQueueFamilyProperties(c.desc.physicalDevice, &familyCount, nullptr);
    std::vector<VkQueueFamilyProperties> families(familyCount);
    c.vk.vkGetPhysicalDeviceQueueFamilyProperties(c.desc.physicalDevice, &familyCount, families.data());
    if (d.asyncQueue && d.asyncQueueFamily >= familyCount) {
      return invalid("AsServiceDesc::asyncQueueFamily " + std::to_string(d.asyncQueueFamily) +
                     " is not a queue family of '" + c.info.deviceName + "' (it has " + std::to_string(familyCount) +
                     "); pass the family asyncQueue was created from");
    }
    const std::string fallback = std::string("; ") + modeName(d.dynamicMode) +
                                 " records the dynamic work in recordPendingWork() instead";
    if (!d.asyncQueue) {
      reason = "AsServiceDesc::asyncQueue is VK_NULL_HANDLE (no second queue was handed over)" + fallback;
    } else if (d.asyncQueueFamily == c.desc.mainQueueFamily) {
      reason = "AsServiceDesc::asyncQueueFamily " + std::to_string(d.asyncQueueFamily) +
               " is the main queue family (ContextDesc::mainQueueFamily)" + fallback;
    } else if (!(families[d.asyncQueueFamily].queueFlags & VK_QUEUE_COMPUTE_BIT)) {
      reason = "AsServiceDesc::asyncQueueFamily " + std::to_string(d.asyncQueueFamily) +
               " has no VK_QUEUE_COMPUTE_BIT" + fallback;
    } else {
      async = true;
      if (Status st = submitter.create(c, d.asyncQueue, d.asyncQueueFamily); !st) return st;
      dynamicStorage = std::make_unique<AsStorageAllocator>(
          ctx, desc.storageBlockBytes, std::vector<uint32_t>{c.desc.mainQueueFamily, d.asyncQueueFamily});
      const uint32_t bits = families[d.asyncQueueFamily].timestampValidBits;
      if (bits > 0 && c.info.timestampPeriodNs > 0.0f) asyncTimestampMask = bits >= 64 ? ~0ull : (1ull << bits) - 1;
    }
  }
  // Enough copies that the copy a build writes is read by no frame in flight (nor by this frame's TLAS).
  switch (d.dynamicMode) {
    case DynamicBuildMode::InFrame: dynamicCopies = 1; break;
    case DynamicBuildMode::AsyncSameFrame: dynamicCopies = async ? frames : 1; break;
    case DynamicBuildMode::AsyncOneFrameLate: dynamicCopies = async ? frames + 1 : 2; break;
  }
  counters.async = async;
  counters.asyncQueueFamily = async ? d.asyncQueueFamily : UINT32_MAX;
  counters.asyncFallbackReason = reason;
  return {};
}

void AccelerationStructureService::Impl::destroyDynamic() {
  // The submitter has waited for the async queue: what waited for it is released with the rest.
  for (AsyncRelease& r : asyncReleases) c.retire(std::move(r.release));
  asyncReleases.clear();
  for (DynamicSubmission& sub : dynamicSubmissions) {
    destroyBuffer(ctx, sub.readback);
    if (sub.timestamps) c.vk.vkDestroyQueryPool(c.desc.device, sub.timestamps, c.allocator());
  }
  dynamicSubmissions.clear();
  for (GpuBuffer& b : freeReadbacks) destroyBuffer(ctx, b);
  freeReadbacks.clear();
  for (VkQueryPool p : freeAsyncTimestampPools) c.vk.vkDestroyQueryPool(c.desc.device, p, c.allocator());
  freeAsyncTimestampPools.clear();
  destroyBuffer(ctx, asyncScratch);
  if (clusterBoundsCreated) clusterBounds.destroy(ctx);
  clusterBoundsCreated = false;
}

void AccelerationStructureService::Impl::retireAfterAsync(std::function<void()> release) {
  if (async && submitter.active() && submitter.lastSubmitted() > submitter.completedValue()) {
    asyncReleases.push_back({submitter.lastSubmitted(), std::move(release)});
  } else {
    retire(std::move(release));
  }
}

void AccelerationStructureService::Impl::retireBufferAfterAsync(GpuBuffer& buffer) {
  if (!buffer.valid()) return;
  GpuBuffer old = std::exchange(buffer, GpuBuffer{});
  Context* context = &ctx;
  retireAfterAsync([context, old]() mutable { destroyBuffer(*context, old); });
}

void AccelerationStructureService::Impl::releaseAsyncRetired() {
  if (asyncReleases.empty()) return;
  const uint64_t done = submitter.completedValue();
  std::vector<AsyncRelease> keep;
  for (AsyncRelease& r : asyncReleases) {
    if (r.value <= done) {
      c.retire(std::move(r.release));  // frames in flight on the main queue may still read it
    } else {
      keep.push_back(std::move(r));
    }
  }
  asyncReleases = std::move(keep);
}

Result<std::vector<BlasCopy>> AccelerationStructureService::Impl::createCopies(const BlasEntry& e) {
  std::vector<BlasCopy> copies(dynamicCopies);
  AsStorageAllocator& pool = copyStorage();
  for (BlasCopy& cp : copies) {
    Result<StorageAllocation> alloc = pool.allocate(e.sizes.accelerationStructureSize);
    Result<VkAccelerationStructureKHR> as = alloc ? createAs(VK_ACCELERATION_STRUCTURE_TYPE_BOTTOM_LEVEL_KHR,
                                                             pool.buffer(alloc->block), alloc->offset,
                                                             e.sizes.accelerationStructureSize)
                                                  : Result<VkAccelerationStructureKHR>(alloc.error());
    if (!as) {
      if (alloc) pool.free(alloc.value());
      retireCopies(copies);
      return as.error();
    }
    cp.as = as.value();
    cp.storage = alloc.value();
    VkAccelerationStructureDeviceAddressInfoKHR ai{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_DEVICE_ADDRESS_INFO_KHR};
    ai.accelerationStructure = cp.as;
    cp.address = c.vk.vkGetAccelerationStructureDeviceAddressKHR(c.desc.device, &ai);
  }
  return copies;
}

void AccelerationStructureService::Impl::retireCopies(std::vector<BlasCopy>& copies) {
  AsStorageAllocator* pool = &copyStorage();
  for (BlasCopy& cp : copies) {
    if (!cp.as) continue;
    VkAccelerationStructureKHR as = cp.as;
    StorageAllocation alloc = cp.storage;
    retireAfterAsync([this, pool, as, alloc] {
      c.vk.vkDestroyAccelerationStructureKHR(c.desc.device, as, c.allocator());
      pool->free(alloc);
    });
  }
  copies.clear();
}

int32_t AccelerationStructureService::Impl::tlasCopy(const BlasEntry& e) const {
  const DynamicBlas& d = e.dyn;
  if (d.copies.empty() || !d.copies[d.newest].written) return -1;
  if (!lateMode()) return static_cast<int32_t>(d.newest);
  // One frame late: the newest copy written in an earlier frame; a mesh built this frame for the first time
  // uses this frame's copy so that it has geometry at all.
  int32_t best = -1;
  for (uint32_t k = 0; k < d.copies.size(); ++k) {
    const BlasCopy& cp = d.copies[k];
    if (cp.written && cp.writtenFrame < c.frame && (best < 0 || cp.writeSerial > d.copies[best].writeSerial)) {
      best = static_cast<int32_t>(k);
    }
  }
  return best >= 0 ? best : static_cast<int32_t>(d.newest);
}

Status AccelerationStructureService::updateMesh(MeshHandle mesh, const MeshUpdate& update) {
  Impl& s = *impl_;
  std::lock_guard<std::mutex> lock(s.mutex);
  s.handOnDeferredRetires();
  Result<Registration*> r = s.lookup(mesh, "updateMesh");
  if (!r) return r.error();
  Registration& reg = *r.value();
  const uint32_t index = reg.blas;
  BlasEntry& e = s.entries[index];
  const std::string name = describe(e.mesh, index);
  if (e.mesh.desc.role != MeshRole::Dynamic) {
    return Error{ErrorCode::InvalidArgument, VK_SUCCESS,
                 "updateMesh: " + name +
                     " was registered with MeshRole::Static; register deforming meshes as MeshRole::Dynamic"};
  }
  if (update.bounds.given()) {
    if (Status st = checkBounds(update.bounds); !st)
      return Error{ErrorCode::InvalidArgument, VK_SUCCESS,
                   "updateMesh: " + name + ": MeshUpdate::" + st.error().message};
  }
  if (update.desc) {
    Result<ValidatedMesh> v = validateMesh(*update.desc, s.c.vk, s.c.desc.physicalDevice, s.c.info.maxPrimitiveCount);
    if (!v) return Error{v.error().code, v.error().vkResult, "updateMesh: MeshUpdate::desc: " + v.error().message};
    const MeshDesc& was = e.mesh.desc;
    const MeshDesc& now = v->desc;
    if (now.role != MeshRole::Dynamic) {
      return Error{ErrorCode::InvalidArgument, VK_SUCCESS,
                   "updateMesh: MeshUpdate::desc of " + name +
                       " has MeshRole::Static; a registered dynamic mesh "
                       "stays dynamic (release it and register it again to make it static)"};
    }
    std::string changes;
    auto change = [&](const char* field, const std::string& a, const std::string& b) {
      if (a != b) changes += std::string(changes.empty() ? "" : ", ") + field + " " + a + " -> " + b;
    };
    change("vertexCount", std::to_string(was.vertexCount), std::to_string(now.vertexCount));
    change("triangleCount", std::to_string(was.triangleCount), std::to_string(now.triangleCount));
    change("vertexFormat", formatName(was.vertexFormat), formatName(now.vertexFormat));
    change("indexType", std::to_string(static_cast<int>(was.indexType)),
           std::to_string(static_cast<int>(now.indexType)));
    change("nonOpaque", was.nonOpaque ? "true" : "false", now.nonOpaque ? "true" : "false");
    if (!changes.empty()) {
      if (!update.forceRebuild) {
        return Error{ErrorCode::InvalidArgument, VK_SUCCESS,
                     "updateMesh: " + name + " changes " + changes +
                         "; a refit keeps the counts and layout of the last build: set MeshUpdate::forceRebuild to "
                         "rebuild the BLAS with the new ones"};
      }
      if (e.refCount > 1) {
        return Error{ErrorCode::InvalidArgument, VK_SUCCESS,
                     "updateMesh: " + name + " changes " + changes + " but its BLAS is shared by " +
                         std::to_string(e.refCount) +
                         " registrations (one MeshDesc::contentKey); register the changed mesh on its own"};
      }
      BlasEntry resized = e;
      resized.mesh = v.value();
      s.queryBuildSizes(resized);
      const VkDeviceSize need = s.storageNeed(resized);
      // The old copies live on until the rebuild has replaced them: the budget counts the new ones from now.
      // (makeRoom evicts only released entries; this one is registered.)
      if (need > e.reserved) {
        if (Status st = s.makeRoom(need - e.reserved, "updateMesh of " + name); !st) return st;
      }
      s.reservedBytes = s.reservedBytes - e.reserved + need;
      e.reserved = need;
      e.sizes = resized.sizes;
      if (e.state == BlasState::Queued) {
        s.retireCopies(e.dyn.copies);  // planned for the old sizes, never written
      } else {
        e.dyn.resize = true;
      }
    }
    reg.mesh = v.value();
    // The BLAS reads the buffers just described, whichever registration sharing it they belong to.
    e.mesh = v.value();
    e.sourceRegistration = mesh.index;
  }
  reg.poseBounds = update.bounds;
  ++e.dyn.pose;
  if (e.state == BlasState::Built) {
    e.dyn.updatePending = true;
    e.dyn.forceRebuild = e.dyn.forceRebuild || update.forceRebuild;
  }
  return {};
}

Status AccelerationStructureService::submitDynamicWork(const AsyncBuildWait& ready) {
  Impl& s = *impl_;
  std::lock_guard<std::mutex> lock(s.mutex);
  s.handOnDeferredRetires();
  if (!s.async) return {};  // recordPendingWork records it
  if (s.lastDynamicWriteFrame == s.c.frame) {
    return Error{ErrorCode::InvalidArgument, VK_SUCCESS,
                 "submitDynamicWork: dynamic work was already submitted in frame " + std::to_string(s.c.frame) +
                     "; call it once per frame, after the frame's updateMesh calls and Context::beginFrame"};
  }
  s.counters.lastFrameRefitTriangles = s.counters.lastFrameRebuildTriangles = 0;
  s.resolveDynamicSubmissions();
  uint64_t trianglesUsed = 0;
  Result<std::vector<DynamicOp>> ops = s.planDynamicWork(trianglesUsed);
  if (!ops) return ops.error();
  if (ops->empty()) return {};
  auto dropPlan = [&] {
    for (DynamicOp& op : ops.value()) s.retireCopies(op.replacement);
  };
  Result<VkCommandBuffer> cmd = s.submitter.begin();
  if (!cmd) {
    dropPlan();
    return cmd.error();
  }
  DynamicSubmission sub;
  std::vector<GpuBuffer> transientScratch;
  auto dropSubmission = [&] {
    if (sub.readback.valid()) s.freeReadbacks.push_back(sub.readback);
    if (sub.timestamps) s.freeAsyncTimestampPools.push_back(sub.timestamps);
    for (GpuBuffer& b : transientScratch) destroyBuffer(s.ctx, b);  // never submitted
    dropPlan();
  };
  if (Status st = s.recordDynamicOps(cmd.value(), ops.value(), true, sub, transientScratch); !st) {
    s.submitter.abandon(cmd.value());
    dropSubmission();
    return st;
  }
  // Builds read the vertex buffers (and the cluster measure reads them in compute shaders).
  const VkPipelineStageFlags readers = VK_PIPELINE_STAGE_ACCELERATION_STRUCTURE_BUILD_BIT_KHR |
                                       VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT;
  Result<uint64_t> value = s.submitter.submit(cmd.value(), ready, readers);
  if (!value) {
    dropSubmission();
    return value.error();
  }
  s.commitDynamicOps(ops.value(), value.value());
  sub.frame = s.c.frame;
  sub.timelineValue = value.value();
  s.dynamicSubmissions.push_back(std::move(sub));
  for (GpuBuffer& b : transientScratch) s.retireBufferAfterAsync(b);
  s.lastVertexReadValue = value.value();
  s.lastDynamicWriteFrame = s.c.frame;
  return {};
}

bool AccelerationStructureService::fillTlasWait(VkSemaphoreSubmitInfo& out) const {
  std::lock_guard<std::mutex> lock(impl_->mutex);
  impl_->handOnDeferredRetires();
  const Impl& s = *impl_;
  if (!s.async) return false;
  uint64_t need = 0;
  for (uint32_t i = 1; i < s.entries.size(); ++i) {
    const BlasEntry& e = s.entries[i];
    if (e.state != BlasState::Built || e.mesh.desc.role != MeshRole::Dynamic) continue;
    const int32_t k = s.tlasCopy(e);
    if (k >= 0) need = std::max(need, e.dyn.copies[k].signalValue);
  }
  if (need == 0) return false;
  out = VkSemaphoreSubmitInfo{VK_STRUCTURE_TYPE_SEMAPHORE_SUBMIT_INFO};
  out.semaphore = s.submitter.semaphore();
  out.value = need;
  out.stageMask = VK_PIPELINE_STAGE_2_ACCELERATION_STRUCTURE_BUILD_BIT_KHR |
                  VK_PIPELINE_STAGE_2_RAY_TRACING_SHADER_BIT_KHR | VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT;
  return true;
}

bool AccelerationStructureService::fillVertexReuseWait(VkSemaphoreSubmitInfo& out) const {
  std::lock_guard<std::mutex> lock(impl_->mutex);
  impl_->handOnDeferredRetires();
  const Impl& s = *impl_;
  if (!s.async || s.lastVertexReadValue == 0) return false;
  out = VkSemaphoreSubmitInfo{VK_STRUCTURE_TYPE_SEMAPHORE_SUBMIT_INFO};
  out.semaphore = s.submitter.semaphore();
  out.value = s.lastVertexReadValue;
  out.stageMask = VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT;  // whatever the engine writes them with
  return true;
}

}  // namespace rb
