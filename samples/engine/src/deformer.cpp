#include "deformer.h"

#include <algorithm>
#include <cstring>

#include "engine_shaders.h"
#include "vk_check.h"

namespace sample_engine::detail {
namespace {

constexpr VkDeviceSize align16(VkDeviceSize v) { return (v + 15) / 16 * 16; }
// Buffers per deforming instance: positions, attributes, last frame's positions.
constexpr size_t kOutputsPerInstance = 3;

// Byte layout of one mesh's static deformation data: joints, weights, morph deltas.
struct SourceLayout {
  VkDeviceSize joints = 0, weights = 0, morph = 0, size = 0;
};

SourceLayout sourceLayout(const MeshData& mesh) {
  const VkDeviceSize n = mesh.positions.size(), influences = mesh.influences();
  SourceLayout l;
  l.joints = 0;
  l.weights = align16(n * influences / 2 * 4);
  l.morph = l.weights + align16(n * influences * 4);
  l.size = l.morph + n * mesh.morphTargets.size() * 24;
  return l;
}

void writeSource(const MeshData& mesh, const SourceLayout& l, char* dst) {
  const size_t n = mesh.positions.size();
  const uint32_t influences = mesh.influences();
  auto* joints = reinterpret_cast<uint32_t*>(dst + l.joints);
  auto* weights = reinterpret_cast<float*>(dst + l.weights);
  for (size_t v = 0; v < n && influences > 0; ++v) {
    for (uint32_t set = 0; set < influences / 4; ++set) {
      const glm::u16vec4 j = set ? mesh.joints1[v] : mesh.joints0[v];
      const glm::vec4 w = set ? mesh.weights1[v] : mesh.weights0[v];
      joints[v * influences / 2 + set * 2] = uint32_t(j.x) | uint32_t(j.y) << 16;
      joints[v * influences / 2 + set * 2 + 1] = uint32_t(j.z) | uint32_t(j.w) << 16;
      for (int k = 0; k < 4; ++k) weights[v * influences + set * 4 + uint32_t(k)] = w[k];
    }
  }
  auto* morph = reinterpret_cast<float*>(dst + l.morph);
  for (size_t t = 0; t < mesh.morphTargets.size(); ++t) {
    const MorphTarget& target = mesh.morphTargets[t];
    for (size_t v = 0; v < n; ++v) {
      float* d = morph + (t * n + v) * 6;
      const glm::vec3 p = target.positionDeltas.empty() ? glm::vec3(0.0f) : target.positionDeltas[v];
      const glm::vec3 nd = target.normalDeltas.empty() ? glm::vec3(0.0f) : target.normalDeltas[v];
      d[0] = p.x, d[1] = p.y, d[2] = p.z, d[3] = nd.x, d[4] = nd.y, d[5] = nd.z;
    }
  }
}

}  // namespace

std::string Deformer::create(Gpu& gpu, const VulkanContext& ctx) {
  gpu_ = &gpu;
  ctx_ = &ctx;
  const VkDevice dev = ctx.device;
  VkSemaphoreTypeCreateInfo type{VK_STRUCTURE_TYPE_SEMAPHORE_TYPE_CREATE_INFO};
  type.semaphoreType = VK_SEMAPHORE_TYPE_TIMELINE;
  type.initialValue = 0;
  VkSemaphoreCreateInfo sci{VK_STRUCTURE_TYPE_SEMAPHORE_CREATE_INFO};
  sci.pNext = &type;
  SE_VK_TRY(vkCreateSemaphore(dev, &sci, nullptr, &timeline_));

  VkPushConstantRange range{VK_SHADER_STAGE_COMPUTE_BIT, 0, sizeof(DeformConstants)};
  VkPipelineLayoutCreateInfo lci{VK_STRUCTURE_TYPE_PIPELINE_LAYOUT_CREATE_INFO};
  lci.pushConstantRangeCount = 1;
  lci.pPushConstantRanges = &range;
  SE_VK_TRY(vkCreatePipelineLayout(dev, &lci, nullptr, &layout_));
  VkShaderModuleCreateInfo mci{VK_STRUCTURE_TYPE_SHADER_MODULE_CREATE_INFO};
  mci.codeSize = sizeof(spirv::deform_comp);
  mci.pCode = spirv::deform_comp;
  VkShaderModule module = VK_NULL_HANDLE;
  SE_VK_TRY(vkCreateShaderModule(dev, &mci, nullptr, &module));
  VkComputePipelineCreateInfo pci{VK_STRUCTURE_TYPE_COMPUTE_PIPELINE_CREATE_INFO};
  pci.stage = {VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO,
               nullptr,
               0,
               VK_SHADER_STAGE_COMPUTE_BIT,
               module,
               "main",
               nullptr};
  pci.layout = layout_;
  VkResult r = vkCreateComputePipelines(dev, VK_NULL_HANDLE, 1, &pci, nullptr, &pipeline_);
  vkDestroyShaderModule(dev, module, nullptr);
  if (r != VK_SUCCESS) return vkFailure("vkCreateComputePipelines (deform)", r);

  for (Slot& slot : slots_) {
    VkCommandPoolCreateInfo cpi{VK_STRUCTURE_TYPE_COMMAND_POOL_CREATE_INFO};
    cpi.flags = VK_COMMAND_POOL_CREATE_RESET_COMMAND_BUFFER_BIT;
    cpi.queueFamilyIndex = ctx.queueFamily;
    SE_VK_TRY(vkCreateCommandPool(dev, &cpi, nullptr, &slot.pool));
    VkCommandBufferAllocateInfo cai{VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO};
    cai.commandPool = slot.pool;
    cai.level = VK_COMMAND_BUFFER_LEVEL_PRIMARY;
    cai.commandBufferCount = 1;
    SE_VK_TRY(vkAllocateCommandBuffers(dev, &cai, &slot.cmd));
    if (ctx.timestampsSupported) {
      VkQueryPoolCreateInfo qci{VK_STRUCTURE_TYPE_QUERY_POOL_CREATE_INFO};
      qci.queryType = VK_QUERY_TYPE_TIMESTAMP;
      qci.queryCount = 2;
      SE_VK_TRY(vkCreateQueryPool(dev, &qci, nullptr, &slot.timestamps));
    }
  }
  return {};
}

void Deformer::destroy() {
  if (!gpu_) return;
  unload();
  const VkDevice dev = ctx_->device;
  for (Slot& slot : slots_) {
    if (slot.timestamps) vkDestroyQueryPool(dev, slot.timestamps, nullptr);
    if (slot.pool) vkDestroyCommandPool(dev, slot.pool, nullptr);
    slot = {};
  }
  if (pipeline_) vkDestroyPipeline(dev, pipeline_, nullptr);
  if (layout_) vkDestroyPipelineLayout(dev, layout_, nullptr);
  if (timeline_) vkDestroySemaphore(dev, timeline_, nullptr);
  pipeline_ = VK_NULL_HANDLE;
  layout_ = VK_NULL_HANDLE;
  timeline_ = VK_NULL_HANDLE;
  gpu_ = nullptr;
}

void Deformer::unload() {
  if (!gpu_) return;
  for (Buffer& b : outputs_) gpu_->destroy(b);
  for (Buffer& b : sources_) gpu_->destroy(b);
  gpu_->destroy(jobs_);
  gpu_->destroy(groupJobs_);
  gpu_->freeBlocks(blocks_);
  for (Slot& slot : slots_) {
    gpu_->destroy(slot.pose);
    slot.timingPending = false;
  }
  instances_.clear();
  bounds_.clear();
  outputs_.clear();
  hasPreviousFrame_ = false;
  sources_.clear();
  pendingWaits_.clear();
  jointBytes_ = weightBytes_ = 0;
  groupCount_ = 0;
}

std::string Deformer::load(GpuScene& scene, const ScenePose& pose) {
  unload();
  const Scene& s = scene.cpu;
  std::vector<uint32_t> deforming;
  for (uint32_t i = 0; i < s.instances.size(); ++i)
    if (deforms(s, s.instances[i]) && !s.meshes[s.instances[i].mesh].positions.empty()) deforming.push_back(i);
  if (deforming.empty()) return {};
  if (!ctx_->bufferDeviceAddressFeature)
    return "the scene has skinned or morphed instances, but the device lacks bufferDeviceAddress (the "
           "deformation pass needs it)";

  // --- Buffers: per-mesh sources, per-instance outputs, the job tables ---
  std::vector<uint32_t> families = {ctx_->queueFamily};
  if (ctx_->asyncComputeFamily != UINT32_MAX) families.push_back(ctx_->asyncComputeFamily);
  VkBufferUsageFlags outputUsage = VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | VK_BUFFER_USAGE_VERTEX_BUFFER_BIT |
                                   VK_BUFFER_USAGE_SHADER_DEVICE_ADDRESS_BIT | VK_BUFFER_USAGE_TRANSFER_SRC_BIT |
                                   VK_BUFFER_USAGE_TRANSFER_DST_BIT;
  if (ctx_->accelerationStructureEnabled)
    outputUsage |= VK_BUFFER_USAGE_ACCELERATION_STRUCTURE_BUILD_INPUT_READ_ONLY_BIT_KHR;
  const VkBufferUsageFlags tableUsage = VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | VK_BUFFER_USAGE_SHADER_DEVICE_ADDRESS_BIT |
                                        VK_BUFFER_USAGE_TRANSFER_DST_BIT;
  sources_.resize(s.meshes.size());
  outputs_.resize(deforming.size() * kOutputsPerInstance);
  std::vector<SourceLayout> layouts(s.meshes.size());
  std::vector<bool> needsSource(s.meshes.size(), false);
  for (uint32_t i : deforming) needsSource[s.instances[i].mesh] = true;
  std::vector<BufferRequest> requests;
  VkDeviceSize stagingSize = 0;
  for (size_t m = 0; m < s.meshes.size(); ++m) {
    if (!needsSource[m]) continue;
    layouts[m] = sourceLayout(s.meshes[m]);
    if (layouts[m].size == 0) continue;
    requests.push_back({layouts[m].size, tableUsage, &sources_[m], {}});
    stagingSize += align16(layouts[m].size);
  }
  for (size_t k = 0; k < deforming.size(); ++k) {
    const VkDeviceSize n = s.meshes[s.instances[deforming[k]].mesh].positions.size();
    requests.push_back({n * 12, outputUsage, &outputs_[kOutputsPerInstance * k], families});
    requests.push_back({n * 36, outputUsage, &outputs_[kOutputsPerInstance * k + 1], families});
    // Read by vertex input only, on the engine's queue.
    requests.push_back({n * 12,
                        VK_BUFFER_USAGE_VERTEX_BUFFER_BIT | VK_BUFFER_USAGE_TRANSFER_DST_BIT,
                        &outputs_[kOutputsPerInstance * k + 2],
                        {}});
  }
  std::vector<DeformJob> jobs(deforming.size());
  std::vector<uint32_t> groupJobs;
  for (size_t k = 0; k < deforming.size(); ++k) {
    const uint32_t n = uint32_t(s.meshes[s.instances[deforming[k]].mesh].positions.size());
    jobs[k].firstGroup = uint32_t(groupJobs.size());
    groupJobs.insert(groupJobs.end(), (n + kDeformGroupSize - 1) / kDeformGroupSize, uint32_t(k));
  }
  groupCount_ = uint32_t(groupJobs.size());
  requests.push_back({jobs.size() * sizeof(DeformJob), tableUsage, &jobs_, {}});
  requests.push_back({groupJobs.size() * 4, tableUsage, &groupJobs_, {}});
  stagingSize += align16(jobs.size() * sizeof(DeformJob)) + align16(groupJobs.size() * 4);
  if (std::string e = gpu_->createBuffers(requests, blocks_); !e.empty()) return e;

  // --- Contents ---
  instances_.resize(deforming.size());
  for (size_t k = 0; k < deforming.size(); ++k) {
    const uint32_t i = deforming[k];
    const Instance& inst = s.instances[i];
    const MeshData& mesh = s.meshes[inst.mesh];
    const Buffer& src = sources_[inst.mesh];
    const SourceLayout& l = layouts[inst.mesh];
    DeformJob& job = jobs[k];
    job.bindPositions = scene.buffers[inst.mesh].positions.address;
    job.bindAttributes = scene.buffers[inst.mesh].attributes.address;
    job.influences = inst.skin >= 0 ? mesh.influences() : 0;
    job.joints = job.influences ? src.address + l.joints : 0;
    job.weights = job.influences ? src.address + l.weights : 0;
    job.targetCount = uint32_t(mesh.morphTargets.size());
    job.morphDeltas = job.targetCount ? src.address + l.morph : 0;
    const Buffer* out = &outputs_[kOutputsPerInstance * k];
    job.outPositions = out[0].address;
    job.outAttributes = out[1].address;
    job.vertexCount = uint32_t(mesh.positions.size());
    job.jointOffset = job.influences ? pose.jointOffset(i) : 0;
    job.weightOffset = job.targetCount ? pose.weightOffset(i) : 0;
    instances_[k] = {i, inst.mesh, out[0].buffer, out[0].address, out[1].buffer, out[1].address, job.vertexCount};
    bounds_.push_back(makeDeformBoundsSource(mesh, job.influences != 0));
    scene.instanceVertices[i] = {out[0].buffer, out[1].buffer, out[2].buffer};
  }
  // The buffers start as copies of the bind pose.
  for (size_t k = 0; k < instances_.size(); ++k)
    poseBounds(bounds_[k], {}, {}, instances_[k].boundsMin, instances_[k].boundsMax);
  Buffer staging;
  if (std::string e = gpu_->createBuffer(stagingSize, VK_BUFFER_USAGE_TRANSFER_SRC_BIT,
                                         VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT | VK_MEMORY_PROPERTY_HOST_COHERENT_BIT,
                                         staging);
      !e.empty())
    return e;
  struct Copy {
    VkBuffer dst;
    VkDeviceSize offset, size;
  };
  std::vector<Copy> copies;
  VkDeviceSize offset = 0;
  char* mapped = static_cast<char*>(staging.mapped);
  for (size_t m = 0; m < s.meshes.size(); ++m) {
    if (!sources_[m].buffer) continue;
    writeSource(s.meshes[m], layouts[m], mapped + offset);
    copies.push_back({sources_[m].buffer, offset, layouts[m].size});
    offset += align16(layouts[m].size);
  }
  std::memcpy(mapped + offset, jobs.data(), jobs.size() * sizeof(DeformJob));
  copies.push_back({jobs_.buffer, offset, jobs.size() * sizeof(DeformJob)});
  offset += align16(jobs.size() * sizeof(DeformJob));
  std::memcpy(mapped + offset, groupJobs.data(), groupJobs.size() * 4);
  copies.push_back({groupJobs_.buffer, offset, groupJobs.size() * 4});
  std::string e = gpu_->submitNow([&](VkCommandBuffer cmd) {
    for (const Copy& c : copies) {
      VkBufferCopy region{c.offset, 0, c.size};
      vkCmdCopyBuffer(cmd, staging.buffer, c.dst, 1, &region);
    }
    // The deformed buffers start as the bind pose, so they are valid before the first frame.
    for (size_t k = 0; k < instances_.size(); ++k) {
      const DeformedInstance& d = instances_[k];
      const MeshBuffers& b = scene.buffers[d.mesh];
      VkBufferCopy positions{0, 0, VkDeviceSize(d.vertexCount) * 12},
          attributes{0, 0, VkDeviceSize(d.vertexCount) * 36};
      vkCmdCopyBuffer(cmd, b.positions.buffer, d.positionBuffer, 1, &positions);
      vkCmdCopyBuffer(cmd, b.attributes.buffer, d.attributeBuffer, 1, &attributes);
      vkCmdCopyBuffer(cmd, b.positions.buffer, previousPositions(k), 1, &positions);
    }
    memoryBarrier(cmd, VK_PIPELINE_STAGE_2_ALL_TRANSFER_BIT, VK_ACCESS_2_TRANSFER_WRITE_BIT,
                  VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT, VK_ACCESS_2_MEMORY_READ_BIT);
  });
  gpu_->destroy(staging);
  if (!e.empty()) return e;

  // --- Per-slot pose buffers: joint matrices, then morph weights ---
  jointBytes_ = pose.packedJointMatrices().size_bytes();
  weightBytes_ = pose.packedMorphWeights().size_bytes();
  for (Slot& slot : slots_)
    if (e = gpu_->createBuffer(std::max<VkDeviceSize>(jointBytes_ + weightBytes_, 64),
                               VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | VK_BUFFER_USAGE_SHADER_DEVICE_ADDRESS_BIT,
                               VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT | VK_MEMORY_PROPERTY_HOST_COHERENT_BIT, slot.pose);
        !e.empty())
      return e;
  return {};
}

void Deformer::updateBounds(const ScenePose& pose) {
  for (size_t k = 0; k < instances_.size(); ++k) {
    DeformedInstance& d = instances_[k];
    poseBounds(bounds_[k], pose.jointMatrices(d.instance), pose.morphWeights(d.instance), d.boundsMin, d.boundsMax);
  }
}

std::string Deformer::submit(uint32_t slot, uint64_t value, const ScenePose& pose) {
  updateBounds(pose);
  Slot& sl = slots_[slot];
  char* mapped = static_cast<char*>(sl.pose.mapped);
  // host-coherent. A model without skins (or without morph targets) has an empty span, whose data() may be null:
  // memcpy from a null pointer is undefined even for 0 bytes (UBSan's nonnull-attribute check).
  if (jointBytes_ != 0) std::memcpy(mapped, pose.packedJointMatrices().data(), jointBytes_);
  if (weightBytes_ != 0) std::memcpy(mapped + jointBytes_, pose.packedMorphWeights().data(), weightBytes_);

  VkCommandBuffer cmd = sl.cmd;
  SE_VK_TRY(vkResetCommandBuffer(cmd, 0));
  VkCommandBufferBeginInfo bi{VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO};
  bi.flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT;
  SE_VK_TRY(vkBeginCommandBuffer(cmd, &bi));
  if (sl.timestamps) {
    vkCmdResetQueryPool(cmd, sl.timestamps, 0, 2);
    vkCmdWriteTimestamp2(cmd, VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT, sl.timestamps, 0);
  }
  // The previous frame's passes (vertex input, and whatever the hook recorded, e.g. BLAS builds) are done
  // with the deformed buffers before they are overwritten.
  memoryBarrier(cmd, VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT, VK_ACCESS_2_MEMORY_WRITE_BIT,
                VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT | VK_PIPELINE_STAGE_2_ALL_TRANSFER_BIT,
                VK_ACCESS_2_SHADER_STORAGE_READ_BIT | VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT |
                    VK_ACCESS_2_TRANSFER_READ_BIT | VK_ACCESS_2_TRANSFER_WRITE_BIT);
  if (hasPreviousFrame_) {
    // Last frame's positions, kept for the pre-pass's motion vectors before the dispatch overwrites them.
    recordKeepPositions(cmd);
    memoryBarrier(cmd, VK_PIPELINE_STAGE_2_ALL_TRANSFER_BIT, VK_ACCESS_2_TRANSFER_READ_BIT,
                  VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT, VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT);
  }
  vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, pipeline_);
  DeformConstants c{};
  c.jobs = jobs_.address;
  c.groupJobs = groupJobs_.address;
  c.jointMatrices = sl.pose.address;
  c.morphWeights = sl.pose.address + jointBytes_;
  c.groupCount = groupCount_;
  const uint32_t maxX = std::max(ctx_->properties.limits.maxComputeWorkGroupCount[0], 1u);
  c.groupsPerRow = std::min(groupCount_, maxX);
  vkCmdPushConstants(cmd, layout_, VK_SHADER_STAGE_COMPUTE_BIT, 0, sizeof(c), &c);
  vkCmdDispatch(cmd, c.groupsPerRow, (groupCount_ + c.groupsPerRow - 1) / c.groupsPerRow, 1);
  if (!hasPreviousFrame_) {
    // The first frame of the scene has no previous one: last frame's positions are this frame's (no motion).
    memoryBarrier(cmd, VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT, VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT,
                  VK_PIPELINE_STAGE_2_ALL_TRANSFER_BIT, VK_ACCESS_2_TRANSFER_READ_BIT);
    recordKeepPositions(cmd);
    hasPreviousFrame_ = true;
  }
  if (sl.timestamps) vkCmdWriteTimestamp2(cmd, VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT, sl.timestamps, 1);
  SE_VK_TRY(vkEndCommandBuffer(cmd));

  VkCommandBufferSubmitInfo cbi{VK_STRUCTURE_TYPE_COMMAND_BUFFER_SUBMIT_INFO};
  cbi.commandBuffer = cmd;
  VkSemaphoreSubmitInfo signal{VK_STRUCTURE_TYPE_SEMAPHORE_SUBMIT_INFO};
  signal.semaphore = timeline_;
  signal.value = value;
  signal.stageMask = VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT;
  VkSubmitInfo2 si{VK_STRUCTURE_TYPE_SUBMIT_INFO_2};
  si.waitSemaphoreInfoCount = uint32_t(pendingWaits_.size());
  si.pWaitSemaphoreInfos = pendingWaits_.data();
  si.commandBufferInfoCount = 1;
  si.pCommandBufferInfos = &cbi;
  si.signalSemaphoreInfoCount = 1;
  si.pSignalSemaphoreInfos = &signal;
  const VkResult r = ctx_->queueSubmit2(ctx_->queue, 1, &si, VK_NULL_HANDLE);
  pendingWaits_.clear();
  if (r != VK_SUCCESS) return vkFailure("vkQueueSubmit2 (deformation)", r);
  sl.timingPending = sl.timestamps != VK_NULL_HANDLE;
  return {};
}

double Deformer::collectTimings(uint32_t slot) {
  Slot& sl = slots_[slot];
  if (!sl.timingPending) return 0.0;
  sl.timingPending = false;
  uint64_t ts[2];
  if (vkGetQueryPoolResults(ctx_->device, sl.timestamps, 0, 2, sizeof(ts), ts, sizeof(uint64_t),
                            VK_QUERY_RESULT_64_BIT) != VK_SUCCESS)
    return 0.0;
  return double(ts[1] - ts[0]) * ctx_->timestampPeriodNs * 1e-6;
}

VkBuffer Deformer::previousPositions(size_t k) const { return outputs_[kOutputsPerInstance * k + 2].buffer; }

void Deformer::recordKeepPositions(VkCommandBuffer cmd) const {
  for (size_t k = 0; k < instances_.size(); ++k) {
    const VkBufferCopy region{0, 0, VkDeviceSize(instances_[k].vertexCount) * 12};
    vkCmdCopyBuffer(cmd, instances_[k].positionBuffer, previousPositions(k), 1, &region);
  }
}

std::string Deformer::readbackPositions(uint32_t index, std::vector<glm::vec3>& out) {
  const DeformedInstance& d = instances_[index];
  const VkDeviceSize size = VkDeviceSize(d.vertexCount) * 12;
  Buffer staging;
  if (std::string e = gpu_->createBuffer(size, VK_BUFFER_USAGE_TRANSFER_DST_BIT,
                                         VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT | VK_MEMORY_PROPERTY_HOST_COHERENT_BIT,
                                         staging);
      !e.empty())
    return e;
  std::string e = gpu_->submitNow([&](VkCommandBuffer cmd) {
    memoryBarrier(cmd, VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT, VK_ACCESS_2_MEMORY_WRITE_BIT,
                  VK_PIPELINE_STAGE_2_ALL_TRANSFER_BIT, VK_ACCESS_2_TRANSFER_READ_BIT);
    VkBufferCopy region{0, 0, size};
    vkCmdCopyBuffer(cmd, d.positionBuffer, staging.buffer, 1, &region);
    memoryBarrier(cmd, VK_PIPELINE_STAGE_2_ALL_TRANSFER_BIT, VK_ACCESS_2_TRANSFER_WRITE_BIT,
                  VK_PIPELINE_STAGE_2_HOST_BIT, VK_ACCESS_2_HOST_READ_BIT);
  });
  if (e.empty()) {
    out.resize(d.vertexCount);
    std::memcpy(out.data(), staging.mapped, size);
  }
  gpu_->destroy(staging);
  return e;
}

}  // namespace sample_engine::detail
