// registerMesh/releaseMesh from streaming threads while the main thread records frames: the handles, the
// dedup, the eviction under a budget and the statistics stay consistent, and a final TLAS traces correctly.
#include <catch2/catch_test_macros.hpp>

#include <algorithm>
#include <atomic>
#include <mutex>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include "test_scene.h"

using namespace rbtest;

namespace {

constexpr int kThreads = 4;
constexpr int kRegistrationsPerThread = 400;
constexpr int kDistinctMeshes = 24;  // contents; each uploaded twice, so content hashes dedup across buffers
constexpr size_t kLivePerThread = 4;
constexpr int kRegistrationsPerFrame = 3;  // per thread: the threads' work spreads over many frames

rbsamples::CpuMesh variant(int i) {
  rbsamples::CpuMesh m = rbsamples::makeSphere(1.0f, 8, 4);
  m.positions[1] += 0.01f * float(i + 1);  // distinct content, same size
  return m;
}

}  // namespace

TEST_CASE("meshes registered and released on other threads while frames are recorded", "[as][threads]") {
  GpuFixture fx;
  // One BLAS's storage, to set a budget that forces evictions from the registration threads.
  VkDeviceSize oneBlas = 0;
  {
    auto probe = rb::AccelerationStructureService::create(fx.ctx());
    RB_REQUIRE_OK(probe);
    UploadedMesh m = fx.upload(variant(0));
    RB_REQUIRE_OK(probe.value()->registerMesh(m.desc));
    fx.runAndSettle([&](VkCommandBuffer cmd) { RB_REQUIRE_OK(probe.value()->recordPendingWork(cmd)); });
    oneBlas = probe.value()->stats().storageUsedBytes;
    probe.value().reset();
    fx.destroy(m);
  }
  REQUIRE(oneBlas > 0);
  rb::AsServiceDesc desc;
  desc.blasBudgetBytes = oneBlas * 20;  // the live set (at most 16) fits; a cache of all 24 contents does not
  desc.disableCompaction = true;        // sizes stay as measured
  auto service = rb::AccelerationStructureService::create(fx.ctx(), desc);
  RB_REQUIRE_OK(service);
  auto& s = *service.value();

  // The engine's buffers are uploaded up front; the threads only describe them to the service.
  std::vector<UploadedMesh> uploads;
  for (int copy = 0; copy < 2; ++copy) {
    for (int i = 0; i < kDistinctMeshes; ++i) uploads.push_back(fx.upload(variant(i)));
  }

  // The handles the main thread may put in a TLAS. A thread removes a handle here before releasing it, and
  // the main thread holds the lock while it builds the TLAS, so a TLAS never names a released handle.
  std::mutex liveMutex;
  std::vector<rb::MeshHandle> live;
  std::atomic<uint32_t> registered{0}, released{0}, outOfBudget{0}, workersDone{0}, frameCounter{0};
  std::mutex errorMutex;
  std::string firstError;
  auto fail = [&](const std::string& what) {
    std::lock_guard<std::mutex> lock(errorMutex);
    if (firstError.empty()) firstError = what;
  };

  auto worker = [&](int t) {
    std::mt19937 rng(1234u + uint32_t(t));
    std::vector<rb::MeshHandle> mine;
    auto releaseOne = [&](size_t k) {
      rb::MeshHandle h = mine[k];
      mine.erase(mine.begin() + std::ptrdiff_t(k));
      {
        std::lock_guard<std::mutex> lock(liveMutex);
        live.erase(std::find(live.begin(), live.end(), h));
      }
      if (rb::Status st = s.releaseMesh(h); !st) {
        fail("releaseMesh: " + st.error().message);
      } else {
        ++released;
      }
    };
    uint32_t frame = 0;
    int thisFrame = 0;
    for (int n = 0; n < kRegistrationsPerThread;) {
      if (thisFrame >= kRegistrationsPerFrame) {
        while (frameCounter.load() == frame) std::this_thread::yield();
        frame = frameCounter.load();
        thisFrame = 0;
      }
      ++thisFrame;
      if (mine.size() >= kLivePerThread) releaseOne(rng() % mine.size());
      const UploadedMesh& m = uploads[rng() % uploads.size()];
      auto h = s.registerMesh(m.desc);
      if (!h) {
        // The BLASes of meshes just released may still be in flight; wait for the frames to move on.
        if (h.error().code != rb::ErrorCode::OutOfBudget) fail("registerMesh: " + h.error().message);
        ++outOfBudget;
        if (!mine.empty()) releaseOne(0);
        std::this_thread::yield();
        continue;
      }
      ++registered;
      ++n;
      mine.push_back(h.value());
      std::lock_guard<std::mutex> lock(liveMutex);
      live.push_back(h.value());
    }
    while (!mine.empty()) releaseOne(mine.size() - 1);
    ++workersDone;
  };

  std::vector<std::thread> threads;
  for (int t = 0; t < kThreads; ++t) threads.emplace_back(worker, t);
  uint32_t frames = 0, tlasInstances = 0;
  while (workersDone.load() < kThreads || frames < 4) {
    fx.runFrame([&](VkCommandBuffer cmd) {
      RB_REQUIRE_OK(s.recordPendingWork(cmd));
      std::vector<rb::Instance> instances;
      std::lock_guard<std::mutex> lock(liveMutex);
      for (rb::MeshHandle h : live) {
        rb::Instance inst;
        inst.mesh = h;
        instances.push_back(inst);
      }
      auto tlas = s.recordTlasBuild(cmd, instances);
      RB_REQUIRE_OK(tlas);
      tlasInstances += tlas->instanceCount;
    });
    (void)s.stats();  // also a recording-thread call that reads what the threads change
    ++frames;
    ++frameCounter;
  }
  for (std::thread& t : threads) t.join();
  INFO(firstError);
  REQUIRE(firstError.empty());
  INFO("frames " << frames << ", TLAS instances " << tlasInstances << ", out of budget " << outOfBudget.load());

  rb::AsStats st = s.stats();
  CHECK(registered.load() == uint32_t(kThreads * kRegistrationsPerThread));
  CHECK(released.load() == registered.load());
  CHECK(st.registrations == registered.load());
  CHECK(st.meshHandles == 0);
  CHECK(st.dedupHits > 0);
  CHECK(st.evictions > 0);  // evicted by registerMesh on the streaming threads
  CHECK(st.blasBytes <= desc.blasBudgetBytes);
  CHECK(tlasInstances > 0);

  // A known set after the storm: three meshes, built and traced against Embree.
  TestScene scene;
  std::vector<rb::Instance> instances;
  std::vector<rb::MeshHandle> handles;
  for (int i = 0; i < 3; ++i) {
    scene.meshes.push_back(variant(i));
    scene.instances.push_back({uint32_t(i), translation(float(i) * 2.5f - 2.5f, 0, 0)});
    auto h = s.registerMesh(uploads[size_t(i)].desc);
    RB_REQUIRE_OK(h);
    handles.push_back(h.value());
    rb::Instance inst;
    inst.mesh = h.value();
    const std::array<float, 12>& transform = scene.instances.back().transform;
    std::copy(transform.begin(), transform.end(), inst.transform);
    inst.customIndex = uint32_t(i);
    instances.push_back(inst);
  }
  rb::TlasInfo tlas;
  fx.runFrame([&](VkCommandBuffer cmd) {
    RB_REQUIRE_OK(s.recordPendingWork(cmd));
    auto t = s.recordTlasBuild(cmd, instances);
    RB_REQUIRE_OK(t);
    tlas = t.value();
  });
  CHECK(tlas.instanceCount == 3);
  for (rb::MeshHandle h : handles) {
    CHECK(s.isBuilt(h).value());
    CHECK(s.blasAddress(h).value() != 0);
  }
  rb::PrimaryRayCamera cam;
  cam.eye[2] = 7.0f;
  cam.target[2] = 0.0f;
  TraceComparison c = compareFirstTrace(fx, scene, tlas.tlas, cam, 64, 64);
  CHECK(c.hitsCompared > 200);
  CHECK(c.distanceAgree == c.hitsCompared);
  CHECK(c.sameInstance == c.hitsCompared);
  for (rb::MeshHandle h : handles) RB_REQUIRE_OK(s.releaseMesh(h));
  CHECK(s.stats().meshHandles == 0);
  CHECK(s.stats().registrations == registered.load() + 3);

  fx.runAndSettle([&](VkCommandBuffer) {});
  service.value().reset();
  for (UploadedMesh& m : uploads) fx.destroy(m);
}

TEST_CASE("validation errors raised on several threads at once are all kept", "[context][validation][threads]") {
  // The debug messenger calls back on the thread that made the Vulkan call: with registerMesh on streaming
  // threads, that is any thread. A deliberate misuse (a zero-sized buffer) on a device of its own, from several
  // threads at once, while this thread reads the count (the ThreadSanitizer job runs this case).
  rb::HeadlessDeviceDesc desc;
  desc.enableValidation = true;
  desc.requireValidation = true;
  auto dev = rb::HeadlessDevice::create(desc);
  RB_REQUIRE_OK(dev);
  rb::HeadlessDevice& device = *dev.value();
  REQUIRE(device.validationEnabled());
  auto createBuffer = reinterpret_cast<PFN_vkCreateBuffer>(device.deviceProc("vkCreateBuffer"));
  auto destroyBuffer = reinterpret_cast<PFN_vkDestroyBuffer>(device.deviceProc("vkDestroyBuffer"));
  constexpr int kCallsPerThread = 100;
  std::atomic<int> running{kThreads};
  std::atomic<bool> go{false};  // all threads start together, so their calls overlap
  auto misuse = [&] {
    while (!go.load()) std::this_thread::yield();
    for (int i = 0; i < kCallsPerThread; ++i) {
      VkBufferCreateInfo info{VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO};
      info.size = 0;  // invalid: size must be greater than 0
      info.usage = VK_BUFFER_USAGE_STORAGE_BUFFER_BIT;
      VkBuffer buffer = VK_NULL_HANDLE;
      if (createBuffer(device.device(), &info, nullptr, &buffer) == VK_SUCCESS && buffer)
        destroyBuffer(device.device(), buffer, nullptr);
    }
    --running;
  };
  std::vector<std::thread> threads;
  for (int t = 0; t < kThreads; ++t) threads.emplace_back(misuse);
  go = true;
  uint32_t seen = 0;
  while (running.load() > 0) {
    seen = std::max(seen, device.validationErrorCount());
    (void)device.validationErrors();
  }
  for (std::thread& t : threads) t.join();
  CHECK(device.validationErrorCount() >= uint32_t(kThreads * kCallsPerThread));
  CHECK(device.validationErrors().size() == device.validationErrorCount());
  CHECK(seen <= device.validationErrorCount());
}
