// Dynamic BLAS work on a real second queue (a compute-only family): the same-frame and one-frame-late scenarios
// with the validation layer (synchronization validation included) watching the cross-queue hand-over. Skips on
// devices without such a family (lavapipe).
#include <catch2/catch_test_macros.hpp>

#include <cmath>
#include <cstring>

#include "dynamic_scene.h"

using namespace rbtest;

namespace {

rbsamples::CpuMesh scaled(const rbsamples::CpuMesh& mesh, float sx, float sy, float sz) {
  rbsamples::CpuMesh out = mesh;
  for (uint32_t v = 0; v < out.vertexCount(); ++v) {
    out.positions[3 * v] *= sx;
    out.positions[3 * v + 1] *= sy;
    out.positions[3 * v + 2] *= sz;
  }
  return out;
}

// Pose k of a breathing, swaying sphere: every pose traces differently.
rbsamples::CpuMesh pose(const rbsamples::CpuMesh& base, uint32_t k) {
  const float t = float(k);
  rbsamples::CpuMesh out = scaled(base, 1.0f + 0.15f * std::sin(t), 1.0f + 0.2f * std::cos(0.7f * t), 1.0f);
  for (uint32_t v = 0; v < out.vertexCount(); ++v) {
    out.positions[3 * v] += 0.3f * std::sin(t + out.positions[3 * v + 1]);
  }
  return out;
}

}  // namespace

TEST_CASE("dynamic BLAS builds on a second queue trace the same-frame and one-frame-late poses", "[dynamic][async]") {
  GpuFixture fx(2, /*requestAsyncComputeQueue=*/true);
  if (!fx.device().asyncComputeQueue()) {
    SKIP("device '" << fx.device().deviceName() << "' has no compute-only queue family; run on a GPU (e.g. H100)");
  }
  const rbsamples::CpuMesh base = rbsamples::makeSphere(1.0f, 32, 16);
  const rbsamples::CpuMesh ground = rbsamples::makeGrid(10.0f, 4);
  rb::PrimaryRayCamera cam;
  const float eye[3] = {0.0f, 3.5f, 7.0f}, target[3] = {0.0f, 1.2f, 0.0f};
  std::memcpy(cam.eye, eye, sizeof eye);
  std::memcpy(cam.target, target, sizeof target);
  auto sceneOf = [&](const rbsamples::CpuMesh& p) {
    TestScene s;
    s.meshes = {p, ground};
    s.instances = {{0, translation(-1.8f, 1.6f, 0)}, {0, translation(1.8f, 1.6f, 0)}, {1, translation(0, 0, 0)}};
    return s;
  };

  for (rb::DynamicBuildMode mode : {rb::DynamicBuildMode::AsyncSameFrame, rb::DynamicBuildMode::AsyncOneFrameLate}) {
    const bool late = mode == rb::DynamicBuildMode::AsyncOneFrameLate;
    INFO((late ? "AsyncOneFrameLate" : "AsyncSameFrame"));
    rb::AsServiceDesc desc;
    desc.dynamicMode = mode;
    desc.asyncQueue = fx.device().asyncComputeQueue();
    desc.asyncQueueFamily = fx.device().asyncComputeQueueFamily();
    desc.refitPolicy.maxRefitsBeforeRebuild = 2;  // rebuilds on the async queue too, not only refits
    auto created = rb::AccelerationStructureService::create(fx.ctx(), desc);
    RB_REQUIRE_OK(created);
    rb::AccelerationStructureService& service = *created.value();
    rb::AsStats st = service.stats();
    INFO(st.asyncFallbackReason);
    REQUIRE(st.async);
    CHECK(st.asyncQueueFamily == fx.device().asyncComputeQueueFamily());
    CHECK(st.asyncFallbackReason.empty());

    DynamicScene dyn(fx, service);
    const uint32_t m = dyn.add(pose(base, 0), "character");
    UploadedMesh groundUpload = fx.upload(ground);
    auto g = service.registerMesh(groundUpload.desc);
    RB_REQUIRE_OK(g);
    const TestScene layout = sceneOf(base);
    std::vector<rb::Instance> instances;
    for (uint32_t i = 0; i < layout.instances.size(); ++i) {
      rb::Instance inst;
      inst.mesh = layout.instances[i].mesh == 0 ? dyn.handle(m) : g.value();
      std::copy(layout.instances[i].transform.begin(), layout.instances[i].transform.end(), inst.transform);
      inst.customIndex = i;
      instances.push_back(inst);
    }

    rb::TlasInfo t = dyn.frame(instances);
    CHECK(t.instanceCount == 3);
    VkSemaphoreSubmitInfo wait{VK_STRUCTURE_TYPE_SEMAPHORE_SUBMIT_INFO};
    CHECK(service.fillTlasWait(wait));  // the first build ran on the async queue, in either mode
    CHECK(service.fillVertexReuseWait(wait));

    // Pose 1 in frame 1: same frame traces it, one frame late still traces pose 0.
    dyn.setPose(m, pose(base, 1).positions);
    t = dyn.frame(instances);
    CHECK(service.stats().staleBlas == (late ? 2u : 0u));
    checkDeformedTraceAgreement(compareFirstTrace(fx, sceneOf(pose(base, late ? 0 : 1)), t.tlas, cam, 64, 48));

    // A run of poses: refits and (every third update) rebuilds on the async queue.
    const uint32_t last = 7;
    for (uint32_t k = 2; k <= last; ++k) {
      dyn.setPose(m, pose(base, k).positions);
      t = dyn.frame(instances);
    }
    CHECK(service.stats().staleBlas == (late ? 2u : 0u));
    checkDeformedTraceAgreement(
        compareFirstTrace(fx, sceneOf(pose(base, late ? last - 1 : last)), t.tlas, cam, 64, 48));
    // No update: both modes trace the newest pose.
    t = dyn.frame(instances);
    CHECK(service.stats().staleBlas == 0);
    checkDeformedTraceAgreement(compareFirstTrace(fx, sceneOf(pose(base, last)), t.tlas, cam, 64, 48));

    st = service.stats();
    CHECK(st.refits + st.rebuilds == last);
    CHECK(st.rebuilds >= 2);
    CHECK(st.lastAsyncGpuMs >= 0.0);
    fx.destroy(groundUpload);
  }
}
