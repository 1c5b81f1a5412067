// Compaction and suballocation statistics add up; eviction frees only BLASes no live TLAS references.
#include <catch2/catch_test_macros.hpp>

#include <algorithm>
#include <cstdio>

#include "test_support.h"

using namespace rbtest;

TEST_CASE("compaction and suballocation statistics add up", "[as][memory]") {
  GpuFixture fx;
  rb::AsServiceDesc desc;
  desc.storageBlockBytes = 1 << 20;  // small blocks so several are used and one mesh gets a dedicated block
  auto service = rb::AccelerationStructureService::create(fx.ctx(), desc);
  RB_REQUIRE_OK(service);
  auto& s = *service.value();

  std::vector<UploadedMesh> meshes;
  std::vector<rb::MeshHandle> handles;
  uint64_t triangles = 0;
  for (uint32_t i = 0; i < 12; ++i) {
    rbsamples::CpuMesh m = rbsamples::makeSphere(1.0f + 0.1f * i, 8 + 4 * i, 4 + 2 * i);
    if (i == 11) m = rbsamples::makeGrid(10.0f, 120);  // 28,800 triangles: larger than one block
    triangles += m.triangleCount();
    meshes.push_back(fx.upload(m));
    auto h = s.registerMesh(meshes.back().desc);
    RB_REQUIRE_OK(h);
    handles.push_back(h.value());
  }
  CHECK(s.stats().blasQueued == 12);
  fx.runAndSettle([&](VkCommandBuffer cmd) {
    auto left = s.recordPendingWork(cmd);
    RB_REQUIRE_OK(left);
    CHECK(left.value() == 0);
  });
  // The compacted sizes are known now; a second call records the copies (or decides to skip them).
  fx.runAndSettle([&](VkCommandBuffer cmd) { RB_REQUIRE_OK(s.recordPendingWork(cmd)); });
  fx.ctx().releaseAfterIdle();

  rb::AsStats st = s.stats();
  CHECK(st.blasCount == 12);
  CHECK(st.blasQueued == 0);
  CHECK(st.triangles == triangles);
  // Every static BLAS was either compacted or its compaction skipped because it saved nothing.
  CHECK(st.blasCompacted + st.compactionsSkipped == 12);
  CHECK(st.blasBytes <= st.blasBytesBeforeCompaction);
  if (fx.ctx().deviceInfo().isCpu) {
    CHECK(st.compactionsSkipped == 12);  // lavapipe reports compacted size == built size
    CHECK(st.blasBytes == st.blasBytesBeforeCompaction);
  }
  CHECK(st.bytesPerTriangle == double(st.blasBytes) / double(st.triangles));

  // Suballocation: BLASes are packed into fewer blocks than BLASes, at 256-byte aligned addresses, and the
  // blocks hold each BLAS's size rounded up to 256 bytes, nothing more.
  for (rb::MeshHandle h : handles) {
    auto addr = s.blasAddress(h);
    RB_REQUIRE_OK(addr);
    CHECK(addr.value() % 256 == 0);
  }
  rb::MemoryStats mem = fx.ctx().memoryStats();
  CHECK(mem.of(rb::MemoryCategory::BlasStorage) >= st.storageBlockBytes);
  CHECK(st.storageBlocks >= 2);
  CHECK(st.storageBlocks < st.blasCount);
  CHECK(st.storageUsedBytes <= st.storageBlockBytes);
  CHECK(st.storageUsedBytes >= st.blasBytes);
  CHECK(st.storageUsedBytes - st.blasBytes < 256 * st.blasCount);

  // Releasing and evicting everything returns the blocks.
  for (rb::MeshHandle h : handles) RB_REQUIRE_OK(s.releaseMesh(h));
  CHECK(s.stats().meshHandles == 0);
  for (UploadedMesh& m : meshes) fx.destroy(m);
}

namespace {

struct EvictionScene {
  std::vector<UploadedMesh> uploads;
  std::vector<rb::MeshHandle> handles;
};

}  // namespace

TEST_CASE("eviction frees unreferenced BLASes, least recently used first, never one a live TLAS uses",
          "[as][memory][eviction]") {
  GpuFixture fx;
  // Measure one BLAS's storage, then set the budget to hold three of them.
  rbsamples::CpuMesh base = rbsamples::makeSphere(1.0f, 24, 12);
  VkDeviceSize oneBlas = 0;
  {
    auto probe = rb::AccelerationStructureService::create(fx.ctx());
    RB_REQUIRE_OK(probe);
    UploadedMesh m = fx.upload(base);
    RB_REQUIRE_OK(probe.value()->registerMesh(m.desc));
    fx.runAndSettle([&](VkCommandBuffer cmd) { RB_REQUIRE_OK(probe.value()->recordPendingWork(cmd)); });
    oneBlas = probe.value()->stats().storageUsedBytes;
    probe.value().reset();
    fx.destroy(m);
  }
  REQUIRE(oneBlas > 0);
  rb::AsServiceDesc desc;
  desc.blasBudgetBytes = oneBlas * 3 + oneBlas / 2;
  desc.disableCompaction = true;  // sizes stay exactly as measured
  auto service = rb::AccelerationStructureService::create(fx.ctx(), desc);
  RB_REQUIRE_OK(service);
  auto& s = *service.value();

  // Four meshes of the same size but different content: A, B, C fit; D needs room.
  std::vector<UploadedMesh> uploads;
  std::vector<rb::MeshHandle> h;
  for (int i = 0; i < 4; ++i) {
    rbsamples::CpuMesh m = base;
    m.positions[1] += 0.01f * float(i + 1);
    uploads.push_back(fx.upload(m));
  }
  for (int i = 0; i < 3; ++i) {
    auto r = s.registerMesh(uploads[i].desc);
    RB_REQUIRE_OK(r);
    h.push_back(r.value());
  }
  // Build them; the TLAS of this frame references B only.
  fx.runAndSettle([&](VkCommandBuffer cmd) {
    RB_REQUIRE_OK(s.recordPendingWork(cmd));
    rb::Instance inst;
    inst.mesh = h[1];
    RB_REQUIRE_OK(s.recordTlasBuild(cmd, std::span(&inst, 1)));
  });

  SECTION("a referenced mesh is never evicted: the budget error names the problem") {
    auto d = s.registerMesh(uploads[3].desc);
    REQUIRE(!d.ok());
    CHECK(d.error().code == rb::ErrorCode::OutOfBudget);
    CHECK(d.error().message.find("blasBudgetBytes") != std::string::npos);
    CHECK(s.stats().evictions == 0);
  }

  SECTION("released meshes are evicted least recently released first, the latest TLAS's mesh is kept") {
    RB_REQUIRE_OK(s.releaseMesh(h[2]));  // C released first
    RB_REQUIRE_OK(s.releaseMesh(h[0]));  // then A
    RB_REQUIRE_OK(s.releaseMesh(h[1]));  // B released but still in the latest TLAS
    auto d = s.registerMesh(uploads[3].desc);
    RB_REQUIRE_OK(d);
    rb::AsStats st = s.stats();
    CHECK(st.evictions == 1);
    CHECK(st.blasCount == 3);  // A, B (cached) and D
    // C was evicted: registering C's content again must build a new BLAS (no dedup hit).
    uint32_t hitsBefore = st.dedupHits;
    auto a = s.registerMesh(uploads[0].desc);  // A is still cached: a dedup hit revives it
    RB_REQUIRE_OK(a);
    CHECK(s.stats().dedupHits == hitsBefore + 1);
  }

  SECTION("a mesh whose TLAS is still in flight is not evicted") {
    // Build a TLAS referencing C, then replace it with one referencing nothing in the same frame slot cycle.
    fx.runFrame([&](VkCommandBuffer cmd) {
      rb::Instance inst;
      inst.mesh = h[2];
      RB_REQUIRE_OK(s.recordTlasBuild(cmd, std::span(&inst, 1)));
    });
    fx.runFrame([&](VkCommandBuffer cmd) { RB_REQUIRE_OK(s.recordTlasBuild(cmd, {})); });
    // C is no longer in the latest TLAS, but the frame that traced it may still be in flight.
    RB_REQUIRE_OK(s.releaseMesh(h[2]));
    auto d = s.registerMesh(uploads[3].desc);
    REQUIRE(!d.ok());
    CHECK(d.error().code == rb::ErrorCode::OutOfBudget);
    // Once those frames are done, C can go.
    for (uint32_t i = 0; i < fx.ctx().framesInFlight(); ++i) fx.ctx().beginFrame();
    auto d2 = s.registerMesh(uploads[3].desc);
    RB_REQUIRE_OK(d2);
    CHECK(s.stats().evictions == 1);
  }
  for (UploadedMesh& m : uploads) fx.destroy(m);
}

namespace {

// What the service holds: its storage blocks and build scratch (AsStats), and the Context's accounting of them.
struct AsHeld {
  VkDeviceSize storage = 0, used = 0, scratch = 0, contextStorage = 0, contextScratch = 0;
};

AsHeld held(GpuFixture& fx, rb::AccelerationStructureService& s) {
  const rb::AsStats st = s.stats();
  const rb::MemoryStats mem = fx.ctx().memoryStats();
  return {st.storageBlockBytes, st.storageUsedBytes, st.scratchBytes, mem.of(rb::MemoryCategory::BlasStorage),
          mem.of(rb::MemoryCategory::Scratch)};
}

// Builds what is queued (and the compaction copies a frame later), then lets the retired objects go.
void settle(GpuFixture& fx, rb::AccelerationStructureService& s) {
  fx.runAndSettle([&](VkCommandBuffer cmd) { RB_REQUIRE_OK(s.recordPendingWork(cmd)); });
  fx.runAndSettle([&](VkCommandBuffer cmd) { RB_REQUIRE_OK(s.recordPendingWork(cmd)); });
  fx.ctx().releaseAfterIdle();
}

}  // namespace

TEST_CASE("acceleration-structure memory follows the content: 1k, then 100k, then 1k triangles", "[as][memory]") {
  GpuFixture fx;
  rb::AsServiceDesc desc;
  desc.releasedCacheBytes = 64 << 10;  // a released 100k-triangle BLAS is more than that: freed at its release
  auto service = rb::AccelerationStructureService::create(fx.ctx(), desc);
  RB_REQUIRE_OK(service);
  auto& s = *service.value();
  UploadedMesh small = fx.upload(rbsamples::makeGrid(10.0f, 22));   // 968 triangles
  UploadedMesh large = fx.upload(rbsamples::makeGrid(10.0f, 224));  // 100,352 triangles
  UploadedMesh other = fx.upload(rbsamples::makeSphere(1.0f, 32, 16));

  auto a = s.registerMesh(small.desc);
  RB_REQUIRE_OK(a);
  settle(fx, s);
  const AsHeld one = held(fx, s);
  auto b = s.registerMesh(large.desc);
  RB_REQUIRE_OK(b);
  settle(fx, s);
  const AsHeld big = held(fx, s);
  RB_REQUIRE_OK(s.releaseMesh(b.value()));
  auto c = s.registerMesh(other.desc);
  RB_REQUIRE_OK(c);
  settle(fx, s);
  const AsHeld during = held(fx, s);
  // The scratch is measured over windows of 64 recording calls; a window that needed at most a quarter of it lets it
  // go (this one started with the large build: the next one).
  for (int i = 0; i < 128; ++i) fx.runFrame([&](VkCommandBuffer cmd) { RB_REQUIRE_OK(s.recordPendingWork(cmd)); });
  fx.ctx().releaseAfterIdle();
  const AsHeld back = held(fx, s);
  std::printf("AS memory (storage held / in use, scratch): 1k triangles %llu / %llu, %llu; 100k %llu / %llu, %llu; "
              "1k again %llu / %llu, %llu, after 128 calls %llu\n",
              (unsigned long long)one.storage, (unsigned long long)one.used, (unsigned long long)one.scratch,
              (unsigned long long)big.storage, (unsigned long long)big.used, (unsigned long long)big.scratch,
              (unsigned long long)during.storage, (unsigned long long)during.used, (unsigned long long)during.scratch,
              (unsigned long long)back.scratch);

  // A small scene reserves what it needs: one 256 KiB block (or its BLAS's size) and its build's scratch, not the
  // 32 MiB block and the 64 MiB scratch budget of the defaults.
  CHECK(one.used > 0);
  CHECK(one.storage <= std::max<VkDeviceSize>(256 << 10, 2 * one.used));
  CHECK(one.scratch > 0);
  CHECK(one.scratch < (4u << 20));
  // Both grow with the content, the blocks at most to twice what is in use (doubling).
  CHECK(big.used > 50 * one.used);
  CHECK(big.storage >= big.used);
  CHECK(big.storage <= 2 * big.used + (256 << 10));
  CHECK(big.scratch >= one.scratch);
  if (!fx.ctx().deviceInfo().isCpu)
    CHECK(big.scratch > one.scratch);  // lavapipe's builds need 8 bytes whatever the size
  // And come back down when it is released: the large BLAS's blocks at once, its scratch within two windows.
  CHECK(during.used < 4 * one.used);
  CHECK(during.storage <= std::max<VkDeviceSize>(256 << 10, 2 * during.used) + one.storage);
  CHECK(during.storage * 8 < big.storage);
  CHECK(back.scratch * 4 < big.scratch);
  CHECK(back.storage == during.storage);
  // The Context counts the same bytes.
  for (const AsHeld& h : {one, big, during, back}) {
    CHECK(h.contextStorage == h.storage);
    CHECK(h.contextScratch == h.scratch);
  }
  RB_REQUIRE_OK(s.releaseMesh(a.value()));
  RB_REQUIRE_OK(s.releaseMesh(c.value()));
  for (UploadedMesh* m : {&small, &large, &other}) fx.destroy(*m);
}

TEST_CASE("released BLASes stay cached within releasedCacheBytes, least recently released go first", "[as][memory]") {
  GpuFixture fx;
  rbsamples::CpuMesh base = rbsamples::makeSphere(1.0f, 24, 12);
  std::vector<UploadedMesh> uploads;
  for (int i = 0; i < 3; ++i) {
    rbsamples::CpuMesh m = base;
    m.positions[1] += 0.01f * float(i + 1);  // same size, different content: no dedup between them
    uploads.push_back(fx.upload(m));
  }
  for (bool disabled : {false, true}) {
    DYNAMIC_SECTION((disabled ? "disableReleasedCache" : "releasedCacheBytes of two BLASes")) {
      rb::AsServiceDesc desc;
      desc.disableCompaction = true;  // sizes stay as built
      auto service = rb::AccelerationStructureService::create(fx.ctx(), desc);
      RB_REQUIRE_OK(service);
      std::vector<rb::MeshHandle> h;
      for (UploadedMesh& u : uploads) {
        auto r = service.value()->registerMesh(u.desc);
        RB_REQUIRE_OK(r);
        h.push_back(r.value());
      }
      settle(fx, *service.value());
      const VkDeviceSize oneBlas = service.value()->stats().storageUsedBytes / 3;
      // The same content again, in a service whose cache holds two of them (or none).
      desc.releasedCacheBytes = 2 * oneBlas + oneBlas / 2;
      desc.disableReleasedCache = disabled;
      for (rb::MeshHandle m : h) RB_REQUIRE_OK(service.value()->releaseMesh(m));
      service.value().reset();
      fx.ctx().releaseAfterIdle();
      auto cached = rb::AccelerationStructureService::create(fx.ctx(), desc);
      RB_REQUIRE_OK(cached);
      rb::AccelerationStructureService& s = *cached.value();
      h.clear();
      for (UploadedMesh& u : uploads) {
        auto r = s.registerMesh(u.desc);
        RB_REQUIRE_OK(r);
        h.push_back(r.value());
      }
      settle(fx, s);
      for (rb::MeshHandle m : h) RB_REQUIRE_OK(s.releaseMesh(m));  // 0 first, 2 last
      rb::AsStats st = s.stats();
      CHECK(st.evictions == (disabled ? 3u : 1u));
      CHECK(st.blasCount == (disabled ? 0u : 2u));
      // A cached one is revived by a registration of its content (a dedup hit), the evicted one is built anew.
      for (int i : {2, 0}) {
        const uint32_t hits = s.stats().dedupHits;
        auto again = s.registerMesh(uploads[size_t(i)].desc);
        RB_REQUIRE_OK(again);
        CHECK(s.stats().dedupHits == hits + ((!disabled && i == 2) ? 1u : 0u));
        RB_REQUIRE_OK(s.releaseMesh(again.value()));
      }
      settle(fx, s);
    }
  }
  for (UploadedMesh& m : uploads) fx.destroy(m);
}
