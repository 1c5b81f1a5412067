#include "dynamic_scene.h"

#include <catch2/catch_test_macros.hpp>

#include <cstring>

namespace rbtest {

DynamicScene::DynamicScene(GpuFixture& fx, rb::AccelerationStructureService& service) : fx_(fx), service_(service) {
  auto s = fx_.device().createTimelineSemaphore();
  RB_REQUIRE_OK(s);
  deform_ = s.value();
}

DynamicScene::~DynamicScene() {
  (void)fx_.device().waitIdle();
  for (Mesh& m : meshes_) {
    fx_.device().destroyBuffer(m.vertices);
    fx_.device().destroyBuffer(m.indices);
  }
  for (rb::HeadlessBuffer& b : retired_) fx_.device().destroyBuffer(b);
  fx_.device().destroySemaphore(deform_);
}

void DynamicScene::queueUpload(uint32_t mesh, bool indices, const void* data, size_t bytes) {
  for (Upload& u : uploads_) {
    if (u.mesh == mesh && u.indices == indices) u.bytes.clear();
  }
  Upload u{mesh, indices, std::vector<uint8_t>(bytes)};
  std::memcpy(u.bytes.data(), data, bytes);
  uploads_.push_back(std::move(u));
}

DynamicScene::Mesh DynamicScene::makeBuffers(const rbsamples::CpuMesh& mesh, const char* debugName) {
  const VkBufferUsageFlags usage = VK_BUFFER_USAGE_SHADER_DEVICE_ADDRESS_BIT |
                                   VK_BUFFER_USAGE_ACCELERATION_STRUCTURE_BUILD_INPUT_READ_ONLY_BIT_KHR |
                                   VK_BUFFER_USAGE_STORAGE_BUFFER_BIT;
  Mesh m;
  auto v = fx_.device().createBuffer(mesh.positions.size() * sizeof(float), usage, false);
  RB_REQUIRE_OK(v);
  auto i = fx_.device().createBuffer(mesh.indices.size() * sizeof(uint32_t), usage, false);
  RB_REQUIRE_OK(i);
  m.vertices = v.value();
  m.indices = i.value();
  m.desc.vertexAddress = m.vertices.address;
  m.desc.vertexBufferBytes = m.vertices.size;
  m.desc.vertexCount = mesh.vertexCount();
  m.desc.indexAddress = m.indices.address;
  m.desc.indexBufferBytes = m.indices.size;
  m.desc.triangleCount = mesh.triangleCount();
  m.desc.role = rb::MeshRole::Dynamic;
  m.desc.debugName = debugName;
  return m;
}

uint32_t DynamicScene::add(const rbsamples::CpuMesh& mesh, const char* debugName) {
  meshes_.push_back(makeBuffers(mesh, debugName));
  Mesh& m = meshes_.back();
  auto h = service_.registerMesh(m.desc);
  RB_REQUIRE_OK(h);
  m.handle = h.value();
  // The buffers are filled by the next deformation submission (the first build waits for it like any other).
  const uint32_t index = static_cast<uint32_t>(meshes_.size() - 1);
  queueUpload(index, false, mesh.positions.data(), mesh.positions.size() * sizeof(float));
  queueUpload(index, true, mesh.indices.data(), mesh.indices.size() * sizeof(uint32_t));
  return index;
}

void DynamicScene::setPose(uint32_t mesh, const std::vector<float>& positions) {
  Mesh& m = meshes_[mesh];
  REQUIRE(positions.size() == size_t(m.desc.vertexCount) * 3);
  queueUpload(mesh, false, positions.data(), positions.size() * sizeof(float));
  m.posePending = true;
}

rb::Status DynamicScene::replace(uint32_t mesh, const rbsamples::CpuMesh& replacement, bool forceRebuild) {
  Mesh& m = meshes_[mesh];
  Mesh next = makeBuffers(replacement, m.desc.debugName);
  rb::MeshUpdate update;
  update.desc = &next.desc;
  update.forceRebuild = forceRebuild;
  rb::Status st = service_.updateMesh(m.handle, update);
  if (!st) {
    fx_.device().destroyBuffer(next.vertices);
    fx_.device().destroyBuffer(next.indices);
    return st;
  }
  // The old buffers may still be read by work in flight: kept until the end.
  retired_.push_back(m.vertices);
  retired_.push_back(m.indices);
  m.vertices = next.vertices;
  m.indices = next.indices;
  m.desc = next.desc;
  queueUpload(mesh, false, replacement.positions.data(), replacement.positions.size() * sizeof(float));
  queueUpload(mesh, true, replacement.indices.data(), replacement.indices.size() * sizeof(uint32_t));
  return st;
}

rb::TlasInfo DynamicScene::frame(std::span<const rb::Instance> instances, const rb::TlasBuildOptions& options) {
  rb::HeadlessDevice& dev = fx_.device();
  const rb::DeviceFunctions& vk = fx_.vk();
  fx_.ctx().beginFrame();

  std::vector<rb::HeadlessBuffer> staging;
  bool uploaded = false;
  for (const Upload& u : uploads_) uploaded = uploaded || !u.bytes.empty();
  if (uploaded) {
    auto cmd = dev.beginCommands();
    RB_REQUIRE_OK(cmd);
    // Earlier frames' builds read these buffers (on this queue; the async queue is covered by the SDK's wait).
    VkMemoryBarrier b{VK_STRUCTURE_TYPE_MEMORY_BARRIER};
    const VkPipelineStageFlags readers = VK_PIPELINE_STAGE_ACCELERATION_STRUCTURE_BUILD_BIT_KHR |
                                         VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT |
                                         VK_PIPELINE_STAGE_RAY_TRACING_SHADER_BIT_KHR;
    vk.vkCmdPipelineBarrier(cmd.value(), readers, VK_PIPELINE_STAGE_TRANSFER_BIT, 0, 1, &b, 0, nullptr, 0, nullptr);
    for (const Upload& u : uploads_) {
      if (u.bytes.empty()) continue;
      auto s = dev.createBuffer(u.bytes.size(), VK_BUFFER_USAGE_TRANSFER_SRC_BIT, true, u.bytes.data());
      RB_REQUIRE_OK(s);
      staging.push_back(s.value());
      VkBufferCopy region{0, 0, u.bytes.size()};
      const Mesh& target = meshes_[u.mesh];
      vk.vkCmdCopyBuffer(cmd.value(), s->buffer, (u.indices ? target.indices : target.vertices).buffer, 1, &region);
    }
    std::vector<VkSemaphoreSubmitInfo> waits;
    VkSemaphoreSubmitInfo reuse{VK_STRUCTURE_TYPE_SEMAPHORE_SUBMIT_INFO};
    if (service_.fillVertexReuseWait(reuse)) waits.push_back(reuse);
    VkSemaphoreSubmitInfo signal{VK_STRUCTURE_TYPE_SEMAPHORE_SUBMIT_INFO};
    signal.semaphore = deform_;
    signal.value = ++deformValue_;
    signal.stageMask = VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT;
    RB_REQUIRE_OK(dev.submitAndWait(cmd.value(), waits, std::span(&signal, 1)));
    for (rb::HeadlessBuffer& s : staging) dev.destroyBuffer(s);
    uploads_.clear();
  }
  for (Mesh& m : meshes_) {
    if (!m.posePending) continue;
    RB_REQUIRE_OK(service_.updateMesh(m.handle));
    m.posePending = false;
  }
  rb::AsyncBuildWait ready;
  if (deformValue_ > 0) ready = {deform_, deformValue_};
  RB_REQUIRE_OK(service_.submitDynamicWork(ready));

  std::vector<VkSemaphoreSubmitInfo> waits;
  if (deformValue_ > 0) {
    VkSemaphoreSubmitInfo w{VK_STRUCTURE_TYPE_SEMAPHORE_SUBMIT_INFO};
    w.semaphore = deform_;
    w.value = deformValue_;
    w.stageMask = VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT;
    waits.push_back(w);
  }
  VkSemaphoreSubmitInfo tlasWait{VK_STRUCTURE_TYPE_SEMAPHORE_SUBMIT_INFO};
  if (service_.fillTlasWait(tlasWait)) waits.push_back(tlasWait);
  auto cmd = dev.beginCommands();
  RB_REQUIRE_OK(cmd);
  RB_REQUIRE_OK(service_.recordPendingWork(cmd.value()));
  auto tlas = service_.recordTlasBuild(cmd.value(), instances, options);
  RB_REQUIRE_OK(tlas);
  RB_REQUIRE_OK(dev.submitAndWait(cmd.value(), waits, {}));
  return tlas.value();
}

std::vector<float> deformed(const rbsamples::CpuMesh& mesh,
                            float (*offset)(uint32_t vertex, int axis, const float* p)) {
  std::vector<float> out = mesh.positions;
  for (uint32_t v = 0; v < mesh.vertexCount(); ++v) {
    for (int a = 0; a < 3; ++a) out[3 * v + a] += offset(v, a, &mesh.positions[3 * v]);
  }
  return out;
}

void checkDeformedTraceAgreement(const TraceComparison& c) {
  INFO("compared " << c.compared << ", hits " << c.hitsCompared << ", hit/miss agree " << c.hitMissAgree
                   << ", distance agree " << c.distanceAgree);
  REQUIRE(c.hitsCompared > 300);
  CHECK(double(c.hitMissAgree) / c.compared >= 0.995);
  CHECK(double(c.distanceAgree) / c.hitsCompared >= 0.995);
}

}  // namespace rbtest
