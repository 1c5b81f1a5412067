// A mesh's queryable state (AccelerationStructureService::meshState, MeshState): Queued until its build is recorded,
// Built after; Failed with the error when its build fails (an injected allocation failure, a budget that cannot hold
// it), without holding up the other meshes, and retried; Evicted by evictMesh, its storage returned to the
// statistics once the frames in flight are done, re-queued by a TLAS build that references it.
#include <catch2/catch_test_macros.hpp>

#include <atomic>
#include <mutex>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include "failure_injection.h"
#include "test_support.h"

using namespace rbtest;

namespace {

rb::Instance instanceOf(rb::MeshHandle mesh, float x) {
  rb::Instance inst;
  inst.mesh = mesh;
  inst.transform[3] = x;
  return inst;
}

// Spheres of one size but different content (no dedup between them), named for the messages.
std::vector<UploadedMesh> uploadSpheres(GpuFixture& fx, int count) {
  static const char* const names[] = {"sphere A", "sphere B", "sphere C", "sphere D"};
  std::vector<UploadedMesh> out;
  for (int i = 0; i < count; ++i) {
    rbsamples::CpuMesh m = rbsamples::makeSphere(1.0f, 24, 12);
    m.positions[1] += 0.01f * float(i + 1);
    out.push_back(fx.upload(m));
    out.back().desc.debugName = names[i];
  }
  return out;
}

rb::MeshState stateOf(const rb::AccelerationStructureService& s, rb::MeshHandle h) {
  auto st = s.meshState(h);
  RB_REQUIRE_OK(st);
  return st.value().state;
}

}  // namespace

TEST_CASE("a mesh is Queued until its build is recorded, then Built", "[as][mesh_state]") {
  GpuFixture fx;
  auto service = rb::AccelerationStructureService::create(fx.ctx());
  RB_REQUIRE_OK(service);
  auto& s = *service.value();
  std::vector<UploadedMesh> uploads = uploadSpheres(fx, 1);
  auto h = s.registerMesh(uploads[0].desc);
  RB_REQUIRE_OK(h);

  auto queued = s.meshState(h.value());
  RB_REQUIRE_OK(queued);
  CHECK(queued.value().state == rb::MeshState::Queued);
  CHECK(queued.value().error.code == rb::ErrorCode::Ok);
  CHECK_FALSE(s.isBuilt(h.value()).value());
  fx.runAndSettle([&](VkCommandBuffer cmd) { RB_REQUIRE_OK(s.recordPendingWork(cmd)); });
  CHECK(stateOf(s, h.value()) == rb::MeshState::Built);
  CHECK(s.isBuilt(h.value()).value());

  // Handles that name no mesh are errors, not states.
  CHECK(s.meshState(rb::MeshHandle{}).error().code == rb::ErrorCode::InvalidArgument);
  RB_REQUIRE_OK(s.releaseMesh(h.value()));
  CHECK(s.meshState(h.value()).error().code == rb::ErrorCode::StaleHandle);
  for (UploadedMesh& m : uploads) fx.destroy(m);
}

TEST_CASE("a mesh whose BLAS cannot be created is Failed with the error, the others are built, a retry builds it",
          "[as][mesh_state][inject]") {
  GpuFixture fx;
  std::vector<UploadedMesh> uploads = uploadSpheres(fx, 2);
  FailureInjector inject(fx.device().getInstanceProcAddr());

  // One engine's frames on a context of its own through the injector; failAt = 0 fails nothing.
  auto run = [&](uint64_t failAt, std::vector<std::string>* log) {
    auto context = rb::Context::create(inject.wrap(fx.device().contextDesc()));
    RB_REQUIRE_OK(context);
    rb::Context& ctx = *context.value();
    auto service = rb::AccelerationStructureService::create(ctx);
    RB_REQUIRE_OK(service);
    auto& s = *service.value();
    auto a = s.registerMesh(uploads[0].desc);
    auto b = s.registerMesh(uploads[1].desc);
    RB_REQUIRE_OK(a);
    RB_REQUIRE_OK(b);
    const rb::Instance both[] = {instanceOf(a.value(), -2.0f), instanceOf(b.value(), 2.0f)};

    inject.reset();
    inject.failCall(failAt);
    ctx.beginFrame();
    auto cmd = fx.device().beginCommands();
    RB_REQUIRE_OK(cmd);
    auto pending = s.recordPendingWork(cmd.value());
    if (log) *log = inject.callLog();
    if (failAt != 0) {
      // The call returns the error of A's build, naming the mesh and the failed Vulkan call; B is built regardless.
      REQUIRE(inject.failures().size() == 1);
      REQUIRE_FALSE(pending.ok());
      const rb::Error& e = pending.error();
      INFO(e.message);
      CHECK(e.code == rb::ErrorCode::VulkanError);
      CHECK(e.vkResult == inject.failures()[0].result);
      CHECK(e.message.find("vkCreateAccelerationStructureKHR") != std::string::npos);
      CHECK(e.message.find("sphere A") != std::string::npos);
      auto failed = s.meshState(a.value());
      RB_REQUIRE_OK(failed);
      CHECK(failed.value().state == rb::MeshState::Failed);
      CHECK(failed.value().error.code == e.code);
      CHECK(failed.value().error.vkResult == e.vkResult);
      CHECK(failed.value().error.message == e.message);
      CHECK(stateOf(s, b.value()) == rb::MeshState::Built);
      CHECK(s.stats().blasFailed == 1);
      // The documented TLAS behaviour: the frame's TLAS holds the meshes that are built, the failed one counted.
      auto tlas = s.recordTlasBuild(cmd.value(), both);
      RB_REQUIRE_OK(tlas);
      CHECK(tlas.value().instanceCount == 1);
      CHECK(tlas.value().failedInstances == 1);
      CHECK(tlas.value().skippedInstances == 0);
    } else {
      RB_REQUIRE_OK(pending);
    }
    RB_REQUIRE_OK(fx.device().submitAndWait(cmd.value()));

    // The next frame retries the build: both meshes are Built and in the TLAS.
    ctx.beginFrame();
    cmd = fx.device().beginCommands();
    RB_REQUIRE_OK(cmd);
    RB_REQUIRE_OK(s.recordPendingWork(cmd.value()));
    auto tlas = s.recordTlasBuild(cmd.value(), both);
    RB_REQUIRE_OK(tlas);
    CHECK(tlas.value().instanceCount == 2);
    CHECK(tlas.value().failedInstances == 0);
    RB_REQUIRE_OK(fx.device().submitAndWait(cmd.value()));
    auto retried = s.meshState(a.value());
    RB_REQUIRE_OK(retried);
    CHECK(retried.value().state == rb::MeshState::Built);
    CHECK(retried.value().error.code == rb::ErrorCode::Ok);
    CHECK(s.stats().blasFailed == 0);

    REQUIRE(fx.device().waitIdle().ok());
    service.value().reset();
    ctx.releaseAfterIdle();
    CHECK(ctx.memoryStats().total() == 0);
    context.value().reset();
    for (const std::string& l : inject.liveObjects()) UNSCOPED_INFO("leaked: " << l);
    CHECK(inject.liveObjects().empty());
    CHECK(inject.misuse().empty());
  };

  // A clean run gives the allocation calls in order: A's acceleration structure is the first one created.
  std::vector<std::string> log;
  run(0, &log);
  uint64_t k = 0;
  for (size_t i = 0; i < log.size() && k == 0; ++i) k = log[i] == "vkCreateAccelerationStructureKHR" ? i + 1 : 0;
  REQUIRE(k > 0);
  run(k, nullptr);
  for (UploadedMesh& m : uploads) fx.destroy(m);
}

TEST_CASE("an evicted mesh frees its BLAS after the frames in flight, and a TLAS build re-queues it",
          "[as][mesh_state][eviction]") {
  GpuFixture fx;
  rb::AsServiceDesc desc;
  desc.disableCompaction = true;  // sizes stay as built
  auto service = rb::AccelerationStructureService::create(fx.ctx(), desc);
  RB_REQUIRE_OK(service);
  auto& s = *service.value();
  std::vector<UploadedMesh> uploads = uploadSpheres(fx, 2);
  auto a = s.registerMesh(uploads[0].desc);
  auto b = s.registerMesh(uploads[1].desc);
  RB_REQUIRE_OK(a);
  RB_REQUIRE_OK(b);
  const rb::Instance both[] = {instanceOf(a.value(), -2.0f), instanceOf(b.value(), 2.0f)};
  fx.runAndSettle([&](VkCommandBuffer cmd) {
    RB_REQUIRE_OK(s.recordPendingWork(cmd));
    RB_REQUIRE_OK(s.recordTlasBuild(cmd, both));
  });
  const rb::AsStats before = s.stats();
  REQUIRE(before.blasCount == 2);

  // The frame that traced A may still be in flight: the storage stays used until framesInFlight frames later.
  fx.runFrame([&](VkCommandBuffer cmd) { RB_REQUIRE_OK(s.recordTlasBuild(cmd, both)); });
  RB_REQUIRE_OK(s.evictMesh(a.value()));
  CHECK(stateOf(s, a.value()) == rb::MeshState::Evicted);
  CHECK(stateOf(s, b.value()) == rb::MeshState::Built);
  CHECK_FALSE(s.isBuilt(a.value()).value());
  CHECK(s.blasAddress(a.value()).error().code == rb::ErrorCode::NotReady);
  rb::AsStats evicted = s.stats();
  CHECK(evicted.blasEvicted == 1);
  CHECK(evicted.blasCount == 1);
  CHECK(evicted.meshEvictions == 1);
  CHECK(evicted.meshHandles == 2);  // the registration stays
  CHECK(evicted.evictedBlasBytes > 0);
  CHECK(evicted.blasBytes + evicted.evictedBlasBytes == before.blasBytes);
  CHECK(evicted.storageUsedBytes == before.storageUsedBytes);
  for (uint32_t i = 0; i < fx.ctx().framesInFlight(); ++i) fx.ctx().beginFrame();
  const rb::AsStats released = s.stats();
  CHECK(released.storageUsedBytes < before.storageUsedBytes);
  CHECK(before.storageUsedBytes - released.storageUsedBytes >= evicted.evictedBlasBytes);
  CHECK(before.storageUsedBytes - released.storageUsedBytes < evicted.evictedBlasBytes + 256);

  // Evicting again does nothing; dynamic meshes and bad handles are refused.
  RB_REQUIRE_OK(s.evictMesh(a.value()));
  CHECK(s.stats().meshEvictions == 1);
  CHECK(s.evictMesh(rb::MeshHandle{}).error().code == rb::ErrorCode::InvalidArgument);
  UploadedMesh deforming = fx.upload(rbsamples::makeSphere(0.5f, 8, 4));
  deforming.desc.role = rb::MeshRole::Dynamic;
  auto d = s.registerMesh(deforming.desc);
  RB_REQUIRE_OK(d);
  auto refused = s.evictMesh(d.value());
  REQUIRE_FALSE(refused.ok());
  CHECK(refused.error().code == rb::ErrorCode::InvalidArgument);
  CHECK(refused.error().message.find("releaseMesh") != std::string::npos);
  RB_REQUIRE_OK(s.releaseMesh(d.value()));

  // A TLAS build that references A re-queues its build and leaves it out this frame; the next frame builds it.
  fx.runFrame([&](VkCommandBuffer cmd) {
    RB_REQUIRE_OK(s.recordPendingWork(cmd));
    auto tlas = s.recordTlasBuild(cmd, both);
    RB_REQUIRE_OK(tlas);
    CHECK(tlas.value().instanceCount == 1);
    CHECK(tlas.value().skippedInstances == 1);
    CHECK(tlas.value().failedInstances == 0);
  });
  CHECK(stateOf(s, a.value()) == rb::MeshState::Queued);
  CHECK(s.stats().blasEvicted == 0);
  CHECK(s.stats().blasQueued == 1);
  fx.runFrame([&](VkCommandBuffer cmd) {
    RB_REQUIRE_OK(s.recordPendingWork(cmd));
    auto tlas = s.recordTlasBuild(cmd, both);
    RB_REQUIRE_OK(tlas);
    CHECK(tlas.value().instanceCount == 2);
  });
  CHECK(stateOf(s, a.value()) == rb::MeshState::Built);

  // A registration of an evicted mesh's geometry shares its BLAS and re-queues it; releasing an evicted mesh works.
  RB_REQUIRE_OK(s.evictMesh(b.value()));
  auto again = s.registerMesh(uploads[1].desc);
  RB_REQUIRE_OK(again);
  CHECK(stateOf(s, b.value()) == rb::MeshState::Queued);
  CHECK(stateOf(s, again.value()) == rb::MeshState::Queued);
  RB_REQUIRE_OK(s.evictMesh(a.value()));
  RB_REQUIRE_OK(s.releaseMesh(a.value()));
  CHECK(s.stats().blasEvicted == 0);
  REQUIRE(fx.device().waitIdle().ok());
  service.value().reset();
  fx.destroy(deforming);
  for (UploadedMesh& m : uploads) fx.destroy(m);
}

TEST_CASE("an evicted mesh the budget cannot hold again is Failed with OutOfBudget until room is made",
          "[as][mesh_state][eviction]") {
  GpuFixture fx;
  std::vector<UploadedMesh> uploads = uploadSpheres(fx, 3);
  // One BLAS's storage, measured; the budget holds two.
  VkDeviceSize oneBlas = 0;
  {
    auto probe = rb::AccelerationStructureService::create(fx.ctx());
    RB_REQUIRE_OK(probe);
    RB_REQUIRE_OK(probe.value()->registerMesh(uploads[0].desc));
    fx.runAndSettle([&](VkCommandBuffer cmd) { RB_REQUIRE_OK(probe.value()->recordPendingWork(cmd)); });
    oneBlas = probe.value()->stats().storageUsedBytes;
  }
  REQUIRE(oneBlas > 0);
  rb::AsServiceDesc desc;
  desc.blasBudgetBytes = oneBlas * 2 + oneBlas / 2;
  desc.disableCompaction = true;
  auto service = rb::AccelerationStructureService::create(fx.ctx(), desc);
  RB_REQUIRE_OK(service);
  auto& s = *service.value();
  std::vector<rb::MeshHandle> h;
  for (int i = 0; i < 2; ++i) {
    auto r = s.registerMesh(uploads[i].desc);
    RB_REQUIRE_OK(r);
    h.push_back(r.value());
  }
  fx.runAndSettle([&](VkCommandBuffer cmd) { RB_REQUIRE_OK(s.recordPendingWork(cmd)); });
  // A makes room for C, which the budget could not hold otherwise.
  RB_REQUIRE_OK(s.evictMesh(h[0]));
  auto c = s.registerMesh(uploads[2].desc);
  RB_REQUIRE_OK(c);
  const rb::Instance ab[] = {instanceOf(h[0], -2.0f), instanceOf(h[1], 2.0f)};

  // The TLAS build cannot re-queue A: A is Failed with the budget's error, the TLAS holds B.
  fx.runFrame([&](VkCommandBuffer cmd) {
    RB_REQUIRE_OK(s.recordPendingWork(cmd));
    auto tlas = s.recordTlasBuild(cmd, ab);
    RB_REQUIRE_OK(tlas);
    CHECK(tlas.value().instanceCount == 1);
    CHECK(tlas.value().failedInstances == 1);
  });
  auto failed = s.meshState(h[0]);
  RB_REQUIRE_OK(failed);
  INFO(failed.value().error.message);
  CHECK(failed.value().state == rb::MeshState::Failed);
  CHECK(failed.value().error.code == rb::ErrorCode::OutOfBudget);
  CHECK(failed.value().error.message.find("sphere A") != std::string::npos);
  CHECK(failed.value().error.message.find("blasBudgetBytes") != std::string::npos);

  // Every recordPendingWork retries it and reports the failed retry; evicting C makes room, and the retry builds A.
  fx.runFrame([&](VkCommandBuffer cmd) {
    auto retry = s.recordPendingWork(cmd);
    REQUIRE_FALSE(retry.ok());
    CHECK(retry.error().code == rb::ErrorCode::OutOfBudget);
  });
  CHECK(stateOf(s, h[0]) == rb::MeshState::Failed);
  RB_REQUIRE_OK(s.evictMesh(c.value()));
  fx.runFrame([&](VkCommandBuffer cmd) {
    RB_REQUIRE_OK(s.recordPendingWork(cmd));
    auto tlas = s.recordTlasBuild(cmd, ab);
    RB_REQUIRE_OK(tlas);
    CHECK(tlas.value().instanceCount == 2);
  });
  CHECK(stateOf(s, h[0]) == rb::MeshState::Built);
  CHECK(stateOf(s, c.value()) == rb::MeshState::Evicted);

  // Evicting a Failed mesh stops its retries.
  RB_REQUIRE_OK(s.evictMesh(h[0]));
  const rb::Instance ca[] = {instanceOf(c.value(), 2.0f), instanceOf(h[0], -2.0f)};
  fx.runFrame([&](VkCommandBuffer cmd) {
    auto tlas = s.recordTlasBuild(cmd, ca);  // C re-queued (room for one), A then cannot be: Failed
    RB_REQUIRE_OK(tlas);
    CHECK(tlas.value().instanceCount == 0);
    CHECK(tlas.value().skippedInstances == 1);
    CHECK(tlas.value().failedInstances == 1);
  });
  CHECK(stateOf(s, h[0]) == rb::MeshState::Failed);
  CHECK(stateOf(s, c.value()) == rb::MeshState::Queued);
  RB_REQUIRE_OK(s.evictMesh(h[0]));
  fx.runFrame([&](VkCommandBuffer cmd) { RB_REQUIRE_OK(s.recordPendingWork(cmd)); });
  CHECK(stateOf(s, h[0]) == rb::MeshState::Evicted);
  CHECK(stateOf(s, c.value()) == rb::MeshState::Built);
  REQUIRE(fx.device().waitIdle().ok());
  service.value().reset();
  for (UploadedMesh& m : uploads) fx.destroy(m);
}

TEST_CASE("meshes evicted and queried on other threads while frames are recorded", "[as][mesh_state][threads]") {
  GpuFixture fx;
  auto service = rb::AccelerationStructureService::create(fx.ctx());
  RB_REQUIRE_OK(service);
  auto& s = *service.value();
  std::vector<UploadedMesh> uploads = uploadSpheres(fx, 4);
  std::vector<rb::MeshHandle> handles;
  std::vector<rb::Instance> instances;
  for (size_t i = 0; i < uploads.size(); ++i) {
    auto h = s.registerMesh(uploads[i].desc);
    RB_REQUIRE_OK(h);
    handles.push_back(h.value());
    instances.push_back(instanceOf(h.value(), 2.5f * float(i)));
  }

  std::atomic<bool> stop{false};
  std::atomic<uint32_t> calls{0};
  std::mutex errorMutex;
  std::string firstError;
  auto worker = [&](uint32_t seed) {
    std::mt19937 rng(seed);
    while (!stop.load()) {
      const rb::MeshHandle h = handles[rng() % handles.size()];
      rb::Status evicted = (rng() % 4 == 0) ? s.evictMesh(h) : rb::Status();
      auto state = s.meshState(h);
      std::lock_guard<std::mutex> lock(errorMutex);
      if (!evicted && firstError.empty()) firstError = "evictMesh: " + evicted.error().message;
      if (!state && firstError.empty()) firstError = "meshState: " + state.error().message;
      if (state && state.value().state == rb::MeshState::Failed && firstError.empty()) {
        firstError = "a mesh failed: " + state.value().error.message;
      }
      ++calls;
      std::this_thread::yield();
    }
  };
  std::vector<std::thread> threads;
  for (uint32_t t = 0; t < 2; ++t) threads.emplace_back(worker, 77u + t);
  // At least 30 frames, and on until the workers have evicted a built mesh: on a loaded machine they may barely run
  // during the first 30 (CI's sanitizer job, this shard beside another on 2 cores, once saw none). At most 3000.
  for (int frame = 0; frame < 3000 && (frame < 30 || s.stats().meshEvictions == 0); ++frame) {
    fx.runFrame([&](VkCommandBuffer cmd) {
      RB_REQUIRE_OK(s.recordPendingWork(cmd));
      auto tlas = s.recordTlasBuild(cmd, instances);
      RB_REQUIRE_OK(tlas);
      CHECK(tlas.value().instanceCount + tlas.value().skippedInstances == instances.size());
      CHECK(tlas.value().failedInstances == 0);
    });
  }
  stop = true;
  for (std::thread& t : threads) t.join();
  INFO(firstError);
  CHECK(firstError.empty());
  CHECK(calls.load() > 0);
  CHECK(s.stats().meshEvictions > 0);

  // Without evictions, the TLAS builds re-queue what is evicted and the next frame has every mesh.
  for (int frame = 0; frame < 2; ++frame) {
    fx.runFrame([&](VkCommandBuffer cmd) {
      RB_REQUIRE_OK(s.recordPendingWork(cmd));
      auto tlas = s.recordTlasBuild(cmd, instances);
      RB_REQUIRE_OK(tlas);
      if (frame == 1) CHECK(tlas.value().instanceCount == instances.size());
    });
  }
  for (rb::MeshHandle h : handles) CHECK(stateOf(s, h) == rb::MeshState::Built);
  fx.runAndSettle([&](VkCommandBuffer) {});
  service.value().reset();
  for (UploadedMesh& m : uploads) fx.destroy(m);
}
