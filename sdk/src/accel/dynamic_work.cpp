// One frame's dynamic BLAS work: the refit/rebuild policy with its staggering, the recording (cluster measure,
// builds and refits into the copies), the commit of the new state, and reading the measures back.
#include <raybridge/acceleration_structures.h>

#include <algorithm>
#include <cmath>

#include "align_up.h"
#include "as_service_impl.h"

namespace rb {

namespace {

struct RebuildCandidate {
  uint32_t entry;
  double ratio;
  uint64_t waitingSince;
};

// Orders the frame's dynamic work after everything on this queue that used the copies, the scratch and the
// readback buffers before: earlier builds and measures, and (main queue) earlier frames' rays through a copy
// that is now rewritten.
void recordDynamicStartBarrier(const DeviceFunctions& vk, VkCommandBuffer cmd, bool onAsyncQueue) {
  VkMemoryBarrier b{VK_STRUCTURE_TYPE_MEMORY_BARRIER};
  b.srcAccessMask = VK_ACCESS_ACCELERATION_STRUCTURE_WRITE_BIT_KHR | VK_ACCESS_SHADER_WRITE_BIT;
  b.dstAccessMask = VK_ACCESS_ACCELERATION_STRUCTURE_READ_BIT_KHR | VK_ACCESS_ACCELERATION_STRUCTURE_WRITE_BIT_KHR |
                    VK_ACCESS_SHADER_WRITE_BIT;
  VkPipelineStageFlags src = VK_PIPELINE_STAGE_ACCELERATION_STRUCTURE_BUILD_BIT_KHR |
                             VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT;
  if (!onAsyncQueue) src |= VK_PIPELINE_STAGE_RAY_TRACING_SHADER_BIT_KHR;
  vk.vkCmdPipelineBarrier(cmd, src,
                          VK_PIPELINE_STAGE_ACCELERATION_STRUCTURE_BUILD_BIT_KHR | VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT,
                          0, 1, &b, 0, nullptr, 0, nullptr);
}

}  // namespace

Result<std::vector<DynamicOp>> AccelerationStructureService::Impl::planDynamicWork(uint64_t& trianglesUsed) {
  std::vector<DynamicOp> ops;
  const bool adaptive = policy.kind == RefitPolicyKind::Adaptive;
  const uint64_t cap = desc.maxBuildTrianglesPerCall;

  // First builds, in slot order, under maxBuildTrianglesPerCall.
  for (uint32_t i = 1; i < entries.size(); ++i) {
    BlasEntry& e = entries[i];
    if (e.state != BlasState::Queued || e.mesh.desc.role != MeshRole::Dynamic) continue;
    const uint64_t tri = e.mesh.desc.triangleCount;
    if (cap && trianglesUsed > 0 && trianglesUsed + tri > cap) break;
    if (e.dyn.copies.empty()) {
      Result<std::vector<BlasCopy>> copies = createCopies(e);
      if (!copies) return copies.error();
      e.dyn.copies = std::move(copies.value());
    }
    DynamicOp op;
    op.kind = DynamicOp::FirstBuild;
    op.entry = i;
    op.dst = 0;
    op.measure = adaptive && ClusterBoundsPass::canMeasure(e.mesh.desc);
    ops.push_back(std::move(op));
    trianglesUsed += tri;
  }

  // Updates: refit unless the policy (or the engine) asks for a rebuild.
  std::vector<DynamicOp> updates;
  std::vector<RebuildCandidate> candidates;
  for (uint32_t i = 1; i < entries.size(); ++i) {
    BlasEntry& e = entries[i];
    if (e.state != BlasState::Built || e.mesh.desc.role != MeshRole::Dynamic || !e.dyn.updatePending) continue;
    const DynamicBlas& d = e.dyn;
    const bool rebuild = d.forceRebuild || d.resize || policy.kind == RefitPolicyKind::AlwaysRebuild;
    if (!rebuild && adaptive && (d.overThreshold || d.refitsSinceBuild >= policy.maxRefitsBeforeRebuild)) {
      if (d.waitingSince == 0) e.dyn.waitingSince = c.frame + 1;  // + 1: 0 means "not waiting"
      candidates.push_back({i, d.ratio, e.dyn.waitingSince});
      continue;
    }
    DynamicOp op;
    op.kind = rebuild ? DynamicOp::Rebuild : DynamicOp::Refit;
    op.entry = i;
    updates.push_back(std::move(op));
  }
  // Staggering: the highest measure first, then the longest waiting; a mesh that does not fit keeps refitting.
  // The first candidate is always taken, so a mesh larger than the whole budget is rebuilt alone.
  std::sort(candidates.begin(), candidates.end(), [](const RebuildCandidate& a, const RebuildCandidate& b) {
    if (a.ratio != b.ratio) return a.ratio > b.ratio;
    if (a.waitingSince != b.waitingSince) return a.waitingSince < b.waitingSince;
    return a.entry < b.entry;
  });
  uint64_t budgetUsed = 0;
  for (const RebuildCandidate& cand : candidates) {
    const uint64_t tri = entries[cand.entry].mesh.desc.triangleCount;
    DynamicOp op;
    op.entry = cand.entry;
    if (budgetUsed == 0 || budgetUsed + tri <= policy.rebuildTrianglesPerFrame) {
      op.kind = DynamicOp::Rebuild;
      budgetUsed += tri;
    } else {
      op.kind = DynamicOp::Refit;
    }
    updates.push_back(std::move(op));
  }

  for (DynamicOp& op : updates) {
    BlasEntry& e = entries[op.entry];
    DynamicBlas& d = e.dyn;
    op.measure = adaptive && ClusterBoundsPass::canMeasure(e.mesh.desc);
    if (d.resize) {
      Result<std::vector<BlasCopy>> copies = createCopies(e);  // e.sizes holds the new sizes
      if (!copies) {
        for (DynamicOp& planned : ops) retireCopies(planned.replacement);
        return copies.error();
      }
      op.replacement = std::move(copies.value());
      op.dst = 0;
      ops.push_back(std::move(op));
      continue;
    }
    op.src = d.newest;
    const uint32_t count = static_cast<uint32_t>(d.copies.size());
    if (count == 1) {
      op.dst = d.newest;  // in place: one queue, ordered by the start barrier
      ops.push_back(std::move(op));
      continue;
    }
    // The next copy of the ring, unless a TLAS that may still be read references it. On the async queue that is
    // any TLAS of a frame in flight (the copy counts make that impossible under the beginFrame contract); on the
    // main queue, earlier frames' rays are ordered before this work by the start barrier, so only a TLAS already
    // recorded in this frame counts. A misuse then delays the update (its instances count as stale) instead of
    // corrupting a frame in flight.
    bool found = false;
    for (uint32_t step = 1; step < count && !found; ++step) {
      const uint32_t k = (d.newest + step) % count;
      const BlasCopy& cp = d.copies[k];
      const bool free = !cp.used || (async ? c.frameDone(cp.lastUsedFrame) : cp.lastUsedFrame != c.frame);
      if (free) {
        op.dst = k;
        found = true;
      }
    }
    if (found) ops.push_back(std::move(op));
  }
  return ops;
}

namespace {

using Impl = AccelerationStructureService::Impl;

// The readback of the cluster measure: one float per cluster of every measured mesh (`clusters` in all).
Status prepareMeasureReadback(Impl& s, const std::vector<DynamicOp>& ops, DynamicSubmission& sub, uint32_t& clusters) {
  clusters = 0;
  for (const DynamicOp& op : ops) {
    if (op.measure) clusters += ClusterBoundsPass::clusterCount(s.entries[op.entry].mesh.desc.triangleCount);
  }
  if (clusters == 0) return {};
  if (!s.clusterBoundsCreated) {
    if (Status st = s.clusterBounds.create(s.ctx); !st) return st;
    s.clusterBoundsCreated = true;
  }
  const VkDeviceSize bytes = VkDeviceSize(clusters) * sizeof(float);
  auto fit = std::find_if(s.freeReadbacks.begin(), s.freeReadbacks.end(),
                          [&](const GpuBuffer& b) { return b.size >= bytes; });
  if (fit != s.freeReadbacks.end()) {
    sub.readback = *fit;
    s.freeReadbacks.erase(fit);
    return {};
  }
  Result<GpuBuffer> b = createBuffer(s.ctx, std::max<VkDeviceSize>(bytes, 4096),
                                     VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | VK_BUFFER_USAGE_SHADER_DEVICE_ADDRESS_BIT,
                                     MemoryLocation::HostVisible, MemoryCategory::Scratch,
                                     "dynamic BLAS cluster measure readback");
  if (!b) return b.error();
  sub.readback = b.value();
  return {};
}

// The build (or refit) description of every op, and the scratch each needs.
struct DynamicBuildInfos {
  std::vector<VkAccelerationStructureGeometryKHR> geometries;
  std::vector<VkAccelerationStructureBuildRangeInfoKHR> ranges;
  std::vector<const VkAccelerationStructureBuildRangeInfoKHR*> rangePtrs;
  std::vector<VkAccelerationStructureBuildGeometryInfoKHR> infos;
  std::vector<VkDeviceSize> scratchNeed;
};

void fillDynamicBuildInfos(const Impl& s, const std::vector<DynamicOp>& ops, DynamicBuildInfos& b,
                           DynamicSubmission& sub) {
  const VkDeviceSize align = s.scratchAlignment();
  b.geometries.resize(ops.size());
  b.ranges.resize(ops.size());
  b.rangePtrs.resize(ops.size());
  b.infos.resize(ops.size());
  b.scratchNeed.resize(ops.size());
  for (size_t i = 0; i < ops.size(); ++i) {
    const DynamicOp& op = ops[i];
    const BlasEntry& e = s.entries[op.entry];
    const std::vector<BlasCopy>& copies = op.replacement.empty() ? e.dyn.copies : op.replacement;
    const bool refit = op.kind == DynamicOp::Refit;
    s.buildGeometry(e, b.geometries[i], b.ranges[i]);
    b.rangePtrs[i] = &b.ranges[i];
    VkAccelerationStructureBuildGeometryInfoKHR& info = b.infos[i];
    info = {VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_BUILD_GEOMETRY_INFO_KHR};
    info.type = VK_ACCELERATION_STRUCTURE_TYPE_BOTTOM_LEVEL_KHR;
    info.flags = s.blasFlags(e);
    info.mode = refit ? VK_BUILD_ACCELERATION_STRUCTURE_MODE_UPDATE_KHR
                      : VK_BUILD_ACCELERATION_STRUCTURE_MODE_BUILD_KHR;
    info.srcAccelerationStructure = refit ? copies[op.src].as : VK_NULL_HANDLE;
    info.dstAccelerationStructure = copies[op.dst].as;
    info.geometryCount = 1;
    info.pGeometries = &b.geometries[i];
    b.scratchNeed[i] = alignUp(refit ? e.sizes.updateScratchSize : e.sizes.buildScratchSize, align);
    sub.triangles += e.mesh.desc.triangleCount;
  }
  sub.builds = static_cast<uint32_t>(ops.size());
}

// Consecutive ops whose scratch is one region: the shared scratch, or transient scratch for a BLAS that alone
// needs more than the budget.
struct ScratchBatch {
  size_t end;
  VkDeviceSize bytes;
  VkDeviceAddress transientBase;  // 0 = the shared scratch
};

// Packs the ops into batches whose scratch fits the budget, creates the scratch they need and points each build
// at its share.
Result<std::vector<ScratchBatch>> placeDynamicScratch(Impl& s, DynamicBuildInfos& b, bool onAsyncQueue,
                                                      std::vector<GpuBuffer>& transientScratch) {
  const VkDeviceSize align = s.scratchAlignment();
  const VkDeviceSize budget = s.desc.scratchBudgetBytes;
  const VkBufferUsageFlags scratchUsage = VK_BUFFER_USAGE_STORAGE_BUFFER_BIT |
                                          VK_BUFFER_USAGE_SHADER_DEVICE_ADDRESS_BIT;
  std::vector<ScratchBatch> batches;
  VkDeviceSize largestShared = 0;
  const size_t count = b.infos.size();
  for (size_t begin = 0; begin < count;) {
    ScratchBatch batch{begin, 0, 0};
    while (batch.end < count && (batch.end == begin || batch.bytes + b.scratchNeed[batch.end] <= budget)) {
      batch.bytes += b.scratchNeed[batch.end++];
    }
    if (batch.bytes > budget) {
      Result<GpuBuffer> t = createBuffer(s.ctx, batch.bytes + align, scratchUsage, MemoryLocation::DeviceLocal,
                                         MemoryCategory::Scratch, "oversized dynamic BLAS scratch");
      if (!t) return t.error();
      transientScratch.push_back(t.value());
      batch.transientBase = alignUp(t->address, align);
    } else {
      largestShared = std::max(largestShared, batch.bytes);
    }
    begin = batch.end;
    batches.push_back(batch);
  }
  VkDeviceAddress sharedBase = 0;
  if (largestShared > 0) {
    // The async queue has scratch of its own (exclusive to its family); both grow to what their batches need.
    Result<VkDeviceAddress> base = onAsyncQueue ? s.growScratch(s.asyncScratch, largestShared, budget,
                                                                "async BLAS build scratch")
                                                : s.sharedScratch(largestShared);
    if (!base) return base.error();
    sharedBase = base.value();
  }
  for (size_t k = 0, begin = 0; k < batches.size(); begin = batches[k++].end) {
    VkDeviceAddress address = batches[k].transientBase ? batches[k].transientBase : sharedBase;
    for (size_t i = begin; i < batches[k].end; ++i) {
      b.infos[i].scratchData.deviceAddress = address;
      address += b.scratchNeed[i];
    }
  }
  return batches;
}

// The measure reads the same vertices as the builds, before them; its results go to the host.
void recordClusterMeasures(Impl& s, VkCommandBuffer cmd, const std::vector<DynamicOp>& ops, uint32_t clusters,
                           DynamicSubmission& sub) {
  uint32_t firstCluster = 0;
  for (const DynamicOp& op : ops) {
    if (!op.measure) continue;
    const BlasEntry& e = s.entries[op.entry];
    ClusterSample sample;
    sample.entry = op.entry;
    sample.entryGeneration = e.generation;
    sample.buildGeneration = e.dyn.buildGeneration + (op.kind == DynamicOp::Refit ? 0u : 1u);
    sample.build = op.kind != DynamicOp::Refit;
    sample.firstCluster = firstCluster;
    sample.clusterCount = ClusterBoundsPass::clusterCount(e.mesh.desc.triangleCount);
    s.clusterBounds.record(s.ctx, cmd, e.mesh.desc,
                           sub.readback.address + VkDeviceAddress(firstCluster) * sizeof(float));
    firstCluster += sample.clusterCount;
    sub.samples.push_back(sample);
  }
  if (clusters > 0) {
    VkMemoryBarrier b{VK_STRUCTURE_TYPE_MEMORY_BARRIER};
    b.srcAccessMask = VK_ACCESS_SHADER_WRITE_BIT;
    b.dstAccessMask = VK_ACCESS_HOST_READ_BIT;
    s.c.vk.vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, VK_PIPELINE_STAGE_HOST_BIT, 0, 1, &b, 0,
                                nullptr, 0, nullptr);
  }
}

}  // namespace

Status AccelerationStructureService::Impl::recordDynamicOps(VkCommandBuffer cmd, std::vector<DynamicOp>& ops,
                                                            bool onAsyncQueue, DynamicSubmission& sub,
                                                            std::vector<GpuBuffer>& transientScratch) {
  // Everything that can fail comes first, so that a failure leaves nothing recorded: the readback of the
  // cluster measure, scratch, the timestamp queries.
  uint32_t clusters = 0;
  if (Status st = prepareMeasureReadback(*this, ops, sub, clusters); !st) return st;
  DynamicBuildInfos builds;
  fillDynamicBuildInfos(*this, ops, builds, sub);
  Result<std::vector<ScratchBatch>> placed = placeDynamicScratch(*this, builds, onAsyncQueue, transientScratch);
  if (!placed) return placed.error();
  const std::vector<ScratchBatch>& batches = placed.value();

  // Timestamps: main-queue work is a BuildBatch (resolved with the others); async work times its submission.
  BuildBatch batchRecord;
  batchRecord.frame = c.frame;
  VkQueryPool timestamps = VK_NULL_HANDLE;
  if (!desc.disableTimestamps && (onAsyncQueue ? asyncTimestampMask != 0 : c.info.timestampsSupported)) {
    Result<VkQueryPool> pool = takeTimestampPool(onAsyncQueue ? freeAsyncTimestampPools : freeTimestampPools,
                                                 "dynamic BLAS timestamps");
    if (!pool) return pool.error();
    timestamps = pool.value();
    (onAsyncQueue ? sub.timestamps : batchRecord.timestamps) = timestamps;
  }

  // Recording.
  if (timestamps) c.vk.vkCmdResetQueryPool(cmd, timestamps, 0, 2);
  recordDynamicStartBarrier(c.vk, cmd, onAsyncQueue);
  if (timestamps) c.vk.vkCmdWriteTimestamp(cmd, VK_PIPELINE_STAGE_ALL_COMMANDS_BIT, timestamps, 0);
  recordClusterMeasures(*this, cmd, ops, clusters, sub);
  for (size_t b = 0, begin = 0; b < batches.size(); begin = batches[b++].end) {
    // Consecutive batches share the scratch memory.
    if (b > 0) recordAsBarrier(c.vk, cmd, VK_PIPELINE_STAGE_ACCELERATION_STRUCTURE_BUILD_BIT_KHR);
    c.vk.vkCmdBuildAccelerationStructuresKHR(cmd, static_cast<uint32_t>(batches[b].end - begin),
                                             builds.infos.data() + begin, builds.rangePtrs.data() + begin);
  }
  if (timestamps) c.vk.vkCmdWriteTimestamp(cmd, VK_PIPELINE_STAGE_ALL_COMMANDS_BIT, timestamps, 1);
  if (!onAsyncQueue) {
    // Visible to this frame's TLAS build and to the rays (the async queue hands over through the semaphore).
    recordAsBarrier(c.vk, cmd,
                    VK_PIPELINE_STAGE_ACCELERATION_STRUCTURE_BUILD_BIT_KHR |
                        VK_PIPELINE_STAGE_RAY_TRACING_SHADER_BIT_KHR | VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT);
    if (batchRecord.timestamps) {
      batchRecord.builds = sub.builds;
      batchRecord.triangles = sub.triangles;
      inFlightBatches.push_back(std::move(batchRecord));
    }
  }
  return {};
}

void AccelerationStructureService::Impl::commitDynamicOps(std::vector<DynamicOp>& ops, uint64_t signalValue) {
  for (DynamicOp& op : ops) {
    BlasEntry& e = entries[op.entry];
    DynamicBlas& d = e.dyn;
    const uint64_t tri = e.mesh.desc.triangleCount;
    if (!op.replacement.empty()) {
      retireCopies(d.copies);
      d.copies = std::move(op.replacement);
      d.resize = false;
    }
    BlasCopy& cp = d.copies[op.dst];
    cp.written = true;
    cp.writeSerial = ++d.writes;
    cp.writtenFrame = c.frame;
    cp.pose = d.pose;
    cp.signalValue = signalValue;
    d.newest = op.dst;
    e.as = cp.as;
    e.address = cp.address;
    d.updatePending = false;
    if (op.kind == DynamicOp::Refit) {
      ++d.refitsSinceBuild;
      ++counters.refits;
      counters.lastFrameRefitTriangles += tri;
      continue;
    }
    ++d.buildGeneration;
    d.refitsSinceBuild = 0;
    d.baselineArea = 0.0;
    d.ratio = 0.0;
    d.overThreshold = false;
    d.waitingSince = 0;
    d.forceRebuild = false;
    e.builtSize = e.currentSize = e.sizes.accelerationStructureSize;
    if (op.kind == DynamicOp::FirstBuild) {
      e.state = BlasState::Built;
    } else {
      ++counters.rebuilds;
      counters.lastFrameRebuildTriangles += tri;
    }
  }
}

Status AccelerationStructureService::Impl::recordDynamicWork(VkCommandBuffer cmd, uint64_t& trianglesUsed,
                                                             bool& recordedAny) {
  // At most one write per copy ring and frame: a second one could overwrite what this frame's TLAS reads.
  if (lastDynamicWriteFrame == c.frame) return {};
  counters.lastFrameRefitTriangles = counters.lastFrameRebuildTriangles = 0;
  resolveDynamicSubmissions();
  Result<std::vector<DynamicOp>> ops = planDynamicWork(trianglesUsed);
  if (!ops) return ops.error();
  if (ops->empty()) return {};
  DynamicSubmission sub;
  std::vector<GpuBuffer> transientScratch;
  Status st = recordDynamicOps(cmd, ops.value(), false, sub, transientScratch);
  for (GpuBuffer& b : transientScratch) retireBuffer(ctx, b);
  if (!st) {
    for (DynamicOp& op : ops.value()) retireCopies(op.replacement);
    if (sub.readback.valid()) retireBuffer(ctx, sub.readback);
    return st;
  }
  commitDynamicOps(ops.value(), 0);
  sub.frame = c.frame;
  if (sub.readback.valid()) dynamicSubmissions.push_back(std::move(sub));
  lastDynamicWriteFrame = c.frame;
  recordedAny = true;
  return {};
}

void AccelerationStructureService::Impl::resolveDynamicSubmissions() {
  releaseAsyncRetired();
  const uint64_t done = async ? submitter.completedValue() : 0;
  size_t resolved = 0;
  // In order: a build's baseline is read before the refits measured against it.
  for (; resolved < dynamicSubmissions.size(); ++resolved) {
    DynamicSubmission& sub = dynamicSubmissions[resolved];
    const bool finished = sub.timelineValue ? sub.timelineValue <= done : c.frameDone(sub.frame);
    if (!finished) break;
    if (sub.timestamps) {
      uint64_t ticks[2] = {0, 0};
      VkResult r = c.vk.vkGetQueryPoolResults(c.desc.device, sub.timestamps, 0, 2, sizeof(ticks), ticks,
                                              sizeof(uint64_t), VK_QUERY_RESULT_64_BIT);
      if (r == VK_NOT_READY) break;
      if (r == VK_SUCCESS) {
        const double ms = double((ticks[1] - ticks[0]) & asyncTimestampMask) * c.info.timestampPeriodNs * 1e-6;
        counters.lastAsyncGpuMs = ms;
        addTiming({sub.frame, sub.builds, sub.triangles, ms});
      }
      freeAsyncTimestampPools.push_back(sub.timestamps);
      sub.timestamps = VK_NULL_HANDLE;
    }
    if (!sub.readback.valid()) continue;
    const float* areas = static_cast<const float*>(sub.readback.mapped);
    for (const ClusterSample& sample : sub.samples) {
      BlasEntry& e = entries[sample.entry];
      if (e.generation != sample.entryGeneration || e.state != BlasState::Built ||
          e.mesh.desc.role != MeshRole::Dynamic || e.dyn.buildGeneration != sample.buildGeneration) {
        continue;  // released, or rebuilt since: measured against a baseline that no longer holds
      }
      double area = 0.0;
      for (uint32_t k = 0; k < sample.clusterCount; ++k) area += areas[sample.firstCluster + k];
      if (!(area > 0.0) || !std::isfinite(area)) continue;  // degenerate (collapsed) pose: no verdict
      DynamicBlas& d = e.dyn;
      if (sample.build) {
        d.baselineArea = area;
      } else if (d.baselineArea > 0.0) {
        d.ratio = area / d.baselineArea;
        d.overThreshold = d.ratio > double(policy.maxAreaGrowth);
      }
    }
    freeReadbacks.push_back(sub.readback);
    sub.readback = GpuBuffer{};
  }
  dynamicSubmissions.erase(dynamicSubmissions.begin(), dynamicSubmissions.begin() + static_cast<ptrdiff_t>(resolved));
}

}  // namespace rb
