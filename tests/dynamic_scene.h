// Plays the engine's part of the animated frame flow for the dynamic BLAS tests: a deformation submission writes
// the dynamic meshes' vertex buffers (a GPU copy that waits on the SDK's vertex-reuse wait) and signals the
// engine's deform timeline; the SDK's async work waits on that value; the main submission (pending work and the
// TLAS) waits on the deformation and on the SDK's TLAS wait. Each submission is waited for on the host before the
// next frame, so the tests make no timing assumptions; the async queue's work still runs beside the main queue's.
#pragma once

#include <span>
#include <vector>

#include "test_scene.h"

namespace rbtest {

class DynamicScene {
 public:
  DynamicScene(GpuFixture& fx, rb::AccelerationStructureService& service);
  ~DynamicScene();  // waits for the device, then frees the buffers

  // Registers `mesh` as MeshRole::Dynamic over buffers that the next frame's deformation submission fills.
  // Returns its index for setPose/replace.
  uint32_t add(const rbsamples::CpuMesh& mesh, const char* debugName = nullptr);
  rb::MeshHandle handle(uint32_t mesh) const { return meshes_[mesh].handle; }
  // The next frame's deformation writes these positions (same vertex count) and calls updateMesh.
  void setPose(uint32_t mesh, const std::vector<float>& positions);
  // Moves the mesh to new buffers holding `mesh` (other counts allowed): calls updateMesh at once with the
  // new description and returns its status; on success the next frame's deformation fills the new buffers.
  rb::Status replace(uint32_t mesh, const rbsamples::CpuMesh& replacement, bool forceRebuild);

  // One frame: beginFrame, deformation (when anything is pending), updateMesh, submitDynamicWork, then the main
  // submission with recordPendingWork and recordTlasBuild.
  rb::TlasInfo frame(std::span<const rb::Instance> instances, const rb::TlasBuildOptions& options = {});

 private:
  struct Mesh {
    rb::HeadlessBuffer vertices, indices;
    rb::MeshDesc desc;
    rb::MeshHandle handle;
    bool posePending = false;
  };
  struct Upload {
    uint32_t mesh;
    bool indices;  // else the vertices
    std::vector<uint8_t> bytes;
  };
  Mesh makeBuffers(const rbsamples::CpuMesh& mesh, const char* debugName);
  // Replaces an upload of the same buffer queued earlier.
  void queueUpload(uint32_t mesh, bool indices, const void* data, size_t bytes);

  GpuFixture& fx_;
  rb::AccelerationStructureService& service_;
  std::vector<Mesh> meshes_;
  std::vector<Upload> uploads_;
  std::vector<rb::HeadlessBuffer> retired_;  // replaced buffers, freed at the end
  VkSemaphore deform_ = VK_NULL_HANDLE;
  uint64_t deformValue_ = 0;
};

// The mesh's positions, each coordinate moved by offset(vertex index, axis, original position).
std::vector<float> deformed(const rbsamples::CpuMesh& mesh, float (*offset)(uint32_t vertex, int axis, const float* p));

// The dynamic tests' bar for a trace of a deformed mesh against Embree: at least 300 hits compared, hit/miss and
// distance agreeing on 99.5% of the rays.
void checkDeformedTraceAgreement(const TraceComparison& c);

}  // namespace rbtest
