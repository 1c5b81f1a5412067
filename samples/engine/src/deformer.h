// GPU skinning and morphing: one compute dispatch per frame writes the deformed vertex buffers of every
// deforming instance (skinned and/or morphed), in a submission of its own that signals a timeline semaphore
// to the frame number. Static from loadScene() on: the job table, the per-mesh skin / morph data and the
// per-instance output buffers; per frame only the joint matrices and morph weights are written (into the
// frame slot's host-visible buffer).
#pragma once

#include <array>
#include <cstddef>
#include <span>
#include <string>
#include <vector>

#include "deform_bounds.h"
#include "gpu_memory.h"
#include "gpu_scene.h"
#include "sample_engine/animation.h"
#include "sample_engine/engine.h"
#include "vk_context.h"

namespace sample_engine::detail {

inline constexpr uint32_t kDeformGroupSize = 64;  // local_size_x of shaders/deform.comp

// Mirror of DeformJob in shaders/deform_job.glsl: one deforming instance.
struct DeformJob {
  VkDeviceAddress bindPositions;
  VkDeviceAddress bindAttributes;
  VkDeviceAddress joints;       // packed 16-bit joint indices, influences / 2 uints per vertex
  VkDeviceAddress weights;      // influences floats per vertex
  VkDeviceAddress morphDeltas;  // targetCount * vertexCount * {position delta, normal delta}
  VkDeviceAddress outPositions;
  VkDeviceAddress outAttributes;
  uint32_t vertexCount;
  uint32_t influences;  // 0, 4 or 8
  uint32_t targetCount;
  uint32_t jointOffset;   // first joint matrix in the frame's pose buffer
  uint32_t weightOffset;  // first morph weight in the frame's pose buffer
  uint32_t firstGroup;
};
static_assert(sizeof(DeformJob) == 80);
static_assert(offsetof(DeformJob, outAttributes) == 48 && offsetof(DeformJob, vertexCount) == 56 &&
              offsetof(DeformJob, firstGroup) == 76);

// Mirror of the push constants in shaders/deform_job.glsl.
struct DeformConstants {
  VkDeviceAddress jobs;
  VkDeviceAddress groupJobs;
  VkDeviceAddress jointMatrices;
  VkDeviceAddress morphWeights;
  uint32_t groupCount;
  uint32_t groupsPerRow;
};
static_assert(sizeof(DeformConstants) == 40);
static_assert(offsetof(DeformConstants, morphWeights) == 24 && offsetof(DeformConstants, groupCount) == 32);

class Deformer {
 public:
  std::string create(Gpu& gpu, const VulkanContext& ctx);
  void destroy();

  // Creates the deforming instances of `scene` (after uploadScene(); the device idle) and points their
  // GpuScene::instanceVertices at the deformed buffers, which start as copies of the bind pose.
  std::string load(GpuScene& scene, const ScenePose& pose);
  void unload();

  bool active() const { return !instances_.empty(); }
  std::span<const DeformedInstance> instances() const { return instances_; }
  VkSemaphore semaphore() const { return active() ? timeline_ : VK_NULL_HANDLE; }
  // Waits the next submit() performs (the hook's PrepassHookInfo::deformWaits).
  std::vector<VkSemaphoreSubmitInfo>& pendingWaits() { return pendingWaits_; }

  // Writes `pose` into frame slot `slot`'s buffer, records and submits the dispatch on the engine's queue
  // (waiting on pendingWaits(), which it empties) and signals the timeline to `value`. The slot's previous
  // frame must have completed.
  std::string submit(uint32_t slot, uint64_t value, const ScenePose& pose);
  // GPU milliseconds of slot's last submission, once its frame completed; 0 when it had none.
  double collectTimings(uint32_t slot);
  // Copies the deformed positions of instances()[index] to the CPU (the device must be idle).
  std::string readbackPositions(uint32_t index, std::vector<glm::vec3>& out);

 private:
  // instances()[k]'s copy of last frame's positions (outputs_' third buffer of the instance).
  VkBuffer previousPositions(size_t k) const;
  // Records the copy of every instance's positions into its last-frame buffer.
  void recordKeepPositions(VkCommandBuffer cmd) const;

  struct Slot {
    VkCommandPool pool = VK_NULL_HANDLE;
    VkCommandBuffer cmd = VK_NULL_HANDLE;
    VkQueryPool timestamps = VK_NULL_HANDLE;
    bool timingPending = false;
    Buffer pose;  // joint matrices, then morph weights (host visible)
  };

  Gpu* gpu_ = nullptr;
  const VulkanContext* ctx_ = nullptr;
  VkPipelineLayout layout_ = VK_NULL_HANDLE;
  VkPipeline pipeline_ = VK_NULL_HANDLE;
  VkSemaphore timeline_ = VK_NULL_HANDLE;
  std::array<Slot, kFramesInFlight> slots_;

  // Per scene.
  std::vector<DeformedInstance> instances_;
  std::vector<DeformBoundsSource> bounds_;   // per instance: what its pose boxes are made of
  void updateBounds(const ScenePose& pose);  // instances_[k].boundsMin/Max for `pose`
  // Per instance: positions, attributes, last frame's positions (copied from the positions before each dispatch
  // overwrites them: the pre-pass's motion vectors).
  std::vector<Buffer> outputs_;
  bool hasPreviousFrame_ = false;  // a submit() since load(): the last-frame positions hold a frame's pose
  std::vector<Buffer> sources_;    // skin + morph data per mesh (empty Buffer for meshes that do not deform)
  Buffer jobs_, groupJobs_;
  std::vector<VkDeviceMemory> blocks_;
  VkDeviceSize jointBytes_ = 0, weightBytes_ = 0;
  uint32_t groupCount_ = 0;
  std::vector<VkSemaphoreSubmitInfo> pendingWaits_;
};

}  // namespace sample_engine::detail
