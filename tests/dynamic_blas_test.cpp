// Dynamic BLASes: refits trace the deformed pose, the refit/rebuild policy and its staggering, the one-frame-late
// mode, the single-queue fallback and mesh replacement. Runs through the in-frame path and the fallback of the
// async modes (lavapipe has one queue); async_blas_test.cpp runs the same scenarios on a second queue.
#include <catch2/catch_test_macros.hpp>

#include <cmath>
#include <cstring>

#include "cluster_bounds.h"
#include "dynamic_scene.h"

using namespace rbtest;

namespace {

// Deterministic per-vertex noise in [-1, 1].
float noise(uint32_t v, int axis) {
  uint32_t h = v * 747796405u + uint32_t(axis) * 2891336453u + 1u;
  h = ((h >> ((h >> 28) + 4)) ^ h) * 277803737u;
  h = (h >> 22) ^ h;
  return float(h & 0xFFFF) / 32767.5f - 1.0f;
}

// A small ripple (1% of the mesh size): refits stay good.
std::vector<float> ripple(const rbsamples::CpuMesh& mesh, float phase) {
  std::vector<float> p = mesh.positions;
  for (uint32_t v = 0; v < mesh.vertexCount(); ++v) p[3 * v + 1] += 0.02f * std::sin(phase + 0.7f * float(v));
  return p;
}

// Every vertex thrown up to `amplitude` in every axis: the boxes of the clusters blow up.
std::vector<float> scrambled(const rbsamples::CpuMesh& mesh, float amplitude) {
  std::vector<float> p = mesh.positions;
  for (uint32_t v = 0; v < mesh.vertexCount(); ++v) {
    for (int a = 0; a < 3; ++a) p[3 * v + a] += amplitude * noise(v, a);
  }
  return p;
}

rbsamples::CpuMesh withPositions(rbsamples::CpuMesh mesh, std::vector<float> positions) {
  mesh.positions = std::move(positions);
  return mesh;
}

rb::Instance instanceOf(rb::MeshHandle mesh, const std::array<float, 12>& t, uint32_t customIndex) {
  rb::Instance inst;
  inst.mesh = mesh;
  std::copy(t.begin(), t.end(), inst.transform);
  inst.customIndex = customIndex;
  return inst;
}

rb::PrimaryRayCamera lookAt(float ex, float ey, float ez, float tx, float ty, float tz) {
  rb::PrimaryRayCamera cam;
  const float eye[3] = {ex, ey, ez}, target[3] = {tx, ty, tz};
  std::memcpy(cam.eye, eye, sizeof eye);
  std::memcpy(cam.target, target, sizeof target);
  return cam;
}

std::unique_ptr<rb::AccelerationStructureService> makeService(GpuFixture& fx, const rb::AsServiceDesc& desc) {
  auto s = rb::AccelerationStructureService::create(fx.ctx(), desc);
  RB_REQUIRE_OK(s);
  return std::move(s.value());
}

}  // namespace

TEST_CASE("a refit after a deformation traces like Embree on the deformed mesh", "[dynamic][embree]") {
  GpuFixture fx;
  rb::AsServiceDesc desc;
  desc.refitPolicy.kind = rb::RefitPolicyKind::AlwaysRefit;  // what is traced is certainly a refit
  auto service = makeService(fx, desc);
  const rbsamples::CpuMesh sphere = rbsamples::makeSphere(1.0f, 32, 16);
  const rbsamples::CpuMesh ground = rbsamples::makeGrid(8.0f, 4);
  DynamicScene dyn(fx, *service);
  const uint32_t m = dyn.add(sphere, "sphere");
  UploadedMesh groundUpload = fx.upload(ground);
  auto groundHandle = service->registerMesh(groundUpload.desc);
  RB_REQUIRE_OK(groundHandle);
  std::vector<rb::Instance> instances = {instanceOf(dyn.handle(m), translation(0, 1, 0), 0),
                                         instanceOf(groundHandle.value(), translation(0, 0, 0), 1)};
  dyn.frame(instances);

  // Bulges of a quarter radius: the old pose's distances are off everywhere on the sphere.
  const rbsamples::CpuMesh wavy = withPositions(sphere, deformed(sphere, [](uint32_t, int axis, const float* p) {
                                                  return p[axis] * 0.25f * std::sin(4.0f * p[1] + 2.0f * p[0]);
                                                }));
  dyn.setPose(m, wavy.positions);
  rb::TlasInfo tlas = dyn.frame(instances);
  rb::AsStats st = service->stats();
  CHECK(st.refits == 1);
  CHECK(st.rebuilds == 0);
  CHECK(st.lastFrameRefitTriangles == sphere.triangleCount());
  CHECK(st.staleBlas == 0);

  TestScene scene;
  scene.meshes = {wavy, ground};
  scene.instances = {{0, translation(0, 1, 0)}, {1, translation(0, 0, 0)}};
  checkDeformedTraceAgreement(compareFirstTrace(fx, scene, tlas.tlas, lookAt(2.2f, 2.6f, 3.0f, 0, 1, 0), 64, 64));
  fx.destroy(groundUpload);
}

TEST_CASE("the adaptive policy rebuilds once the cluster measure passes its threshold", "[dynamic][policy]") {
  GpuFixture fx;
  auto service = makeService(fx, {});                                        // Adaptive, kDefaultMaxAreaGrowth
  const rbsamples::CpuMesh grid = rbsamples::makeBumpyGrid(4.0f, 16, 0.1f);  // 512 triangles, 8 clusters
  DynamicScene dyn(fx, *service);
  const uint32_t m = dyn.add(grid);
  const std::vector<rb::Instance> instances = {instanceOf(dyn.handle(m), translation(0, 0, 0), 0)};
  dyn.frame(instances);

  // Small deformations keep refitting, however long their measures have had to come back.
  for (uint32_t k = 1; k <= 5; ++k) {
    dyn.setPose(m, ripple(grid, float(k)));
    dyn.frame(instances);
    CHECK(service->stats().refits == k);
    CHECK(service->stats().rebuilds == 0);
  }
  // Thrown apart: the measure grows several times over, a rebuild follows within a few frames (its readback
  // lags by the frames in flight). Until then the mesh keeps refitting.
  const std::vector<float> thrown = scrambled(grid, 1.0f);
  uint32_t frames = 0;
  while (service->stats().rebuilds == 0 && frames < 6) {
    dyn.setPose(m, thrown);
    dyn.frame(instances);
    ++frames;
  }
  rb::AsStats st = service->stats();
  INFO("frames until the rebuild: " << frames);
  REQUIRE(st.rebuilds == 1);
  CHECK(frames >= 2);  // the decision waits for the measure
  CHECK(st.lastFrameRebuildTriangles == grid.triangleCount());
  CHECK(st.lastFrameRefitTriangles == 0);
  // Measured against the new build, the same pose refits again.
  for (uint32_t k = 0; k < 4; ++k) {
    dyn.setPose(m, thrown);
    dyn.frame(instances);
  }
  CHECK(service->stats().rebuilds == 1);
  CHECK(service->stats().refits == st.refits + 4);
}

TEST_CASE("the refit measure declines meshes its 32-bit indexing cannot reach", "[dynamic][policy]") {
  // The measure's shader indexes words as triangle * 3 + corner and vertex * stride / 4 in 32 bits, which SPIR-V
  // takes as signed: a mesh past INT32_MAX would read the wrong words (or out of bounds) and decide rebuilds from
  // garbage; it rebuilds by refit count instead.
  rb::MeshDesc m;
  m.vertexAddress = 1 << 16;
  m.indexAddress = 1 << 20;
  m.vertexFormat = VK_FORMAT_R32G32B32_SFLOAT;
  m.vertexStride = 12;
  m.indexType = rb::IndexType::Uint32;
  m.vertexCount = 1000000;
  m.triangleCount = 1000000;
  m.indexBufferBytes = uint64_t(m.triangleCount) * 12;
  CHECK(rb::ClusterBoundsPass::canMeasure(m));
  SECTION("715,827,882 triangles are the most") {
    m.triangleCount = 715827882u;  // the last index word: 2,147,483,645
    m.indexBufferBytes = uint64_t(m.triangleCount) * 12;
    CHECK(rb::ClusterBoundsPass::canMeasure(m));
    m.triangleCount = 715827883u;
    m.indexBufferBytes = uint64_t(m.triangleCount) * 12;
    CHECK_FALSE(rb::ClusterBoundsPass::canMeasure(m));
  }
  SECTION("positions past 8 GiB") {
    m.vertexCount = 715827882u;  // 12 bytes each: the last word read is 2,147,483,645
    CHECK(rb::ClusterBoundsPass::canMeasure(m));
    m.vertexStride = 16;  // 4 words each: the last at 2,863,311,526
    CHECK_FALSE(rb::ClusterBoundsPass::canMeasure(m));
  }
  SECTION("without indices") {
    m.indexType = rb::IndexType::None;
    m.vertexCount = 3 * 715827883u;
    m.triangleCount = 715827883u;
    CHECK_FALSE(rb::ClusterBoundsPass::canMeasure(m));
  }
}

TEST_CASE("refit counts and the fixed policies decide rebuilds exactly", "[dynamic][policy]") {
  GpuFixture fx;
  const rbsamples::CpuMesh grid = rbsamples::makeGrid(2.0f, 6);
  auto run = [&](const rb::RefitPolicy& policy, bool scramble, auto&& check) {
    rb::AsServiceDesc desc;
    desc.refitPolicy = policy;
    auto service = makeService(fx, desc);
    DynamicScene dyn(fx, *service);
    const uint32_t m = dyn.add(grid);
    const std::vector<rb::Instance> instances = {instanceOf(dyn.handle(m), translation(0, 0, 0), 0)};
    dyn.frame(instances);
    for (uint32_t update = 1; update <= 8; ++update) {
      dyn.setPose(m, scramble ? scrambled(grid, 0.5f * float(update)) : ripple(grid, float(update)));
      dyn.frame(instances);
      INFO("update " << update);
      check(update, service->stats());
    }
  };
  SECTION("maxRefitsBeforeRebuild: the update after three refits rebuilds") {
    rb::RefitPolicy p;
    p.maxAreaGrowth = 1e6f;  // only the count decides
    p.maxRefitsBeforeRebuild = 3;
    run(p, false, [](uint32_t update, const rb::AsStats& st) {
      CHECK(st.rebuilds == update / 4);
      CHECK(st.refits == update - update / 4);
    });
  }
  SECTION("AlwaysRebuild rebuilds every update, AlwaysRefit never") {
    rb::RefitPolicy rebuild;
    rebuild.kind = rb::RefitPolicyKind::AlwaysRebuild;
    rebuild.rebuildTrianglesPerFrame = 1;  // not staggered
    run(rebuild, false, [&](uint32_t update, const rb::AsStats& st) {
      CHECK(st.rebuilds == update);
      CHECK(st.refits == 0);
      CHECK(st.lastFrameRebuildTriangles == grid.triangleCount());
    });
    rb::RefitPolicy refit;
    refit.kind = rb::RefitPolicyKind::AlwaysRefit;
    run(refit, true, [](uint32_t update, const rb::AsStats& st) {
      CHECK(st.rebuilds == 0);
      CHECK(st.refits == update);
    });
  }
}

TEST_CASE("staggered rebuilds never exceed the per-frame budget and reach every mesh", "[dynamic][policy]") {
  GpuFixture fx;
  rb::AsServiceDesc desc;
  desc.refitPolicy.rebuildTrianglesPerFrame = 300;  // two small meshes a frame
  SECTION("in frame, one copy rebuilt in place") { desc.dynamicMode = rb::DynamicBuildMode::InFrame; }
  SECTION("one frame late (fallback), rebuilds into the next copy") {
    desc.dynamicMode = rb::DynamicBuildMode::AsyncOneFrameLate;
  }
  auto service = makeService(fx, desc);
  DynamicScene dyn(fx, *service);
  std::vector<rbsamples::CpuMesh> meshes(10, rbsamples::makeBumpyGrid(2.0f, 8, 0.05f));  // 128 triangles each
  meshes.push_back(rbsamples::makeBumpyGrid(2.0f, 16, 0.05f));  // 512: larger than the whole budget
  std::vector<rb::Instance> instances;
  for (uint32_t i = 0; i < meshes.size(); ++i) {
    const uint32_t m = dyn.add(meshes[i]);
    instances.push_back(instanceOf(dyn.handle(m), translation(3.0f * float(i), 0, 0), i));
  }
  dyn.frame(instances);
  CHECK(service->stats().rebuilds == 0);  // first builds are not rebuilds

  const uint64_t expected = meshes.size();
  uint32_t frames = 0, framesWithRebuilds = 0, bigAlone = 0;
  while (service->stats().rebuilds < expected && frames < 20) {
    for (uint32_t i = 0; i < meshes.size(); ++i) dyn.setPose(i, scrambled(meshes[i], 0.8f));
    dyn.frame(instances);
    ++frames;
    const rb::AsStats st = service->stats();
    INFO("frame " << frames << ": " << st.lastFrameRebuildTriangles << " triangles rebuilt");
    // Within the budget, or the large mesh alone.
    CHECK((st.lastFrameRebuildTriangles <= 300 || st.lastFrameRebuildTriangles == 512));
    bigAlone += st.lastFrameRebuildTriangles == 512 ? 1 : 0;
    framesWithRebuilds += st.lastFrameRebuildTriangles > 0 ? 1 : 0;
    // Every updated mesh is refit or rebuilt in every frame: the waiting ones keep refitting.
    CHECK(st.lastFrameRefitTriangles + st.lastFrameRebuildTriangles == 10 * 128 + 512);
  }
  CHECK(service->stats().rebuilds == expected);
  CHECK(bigAlone == 1);
  CHECK(framesWithRebuilds >= 6);  // five frames of two small meshes, one of the large one
  // Rebuilt against the thrown pose, they refit from now on.
  for (uint32_t i = 0; i < meshes.size(); ++i) dyn.setPose(i, scrambled(meshes[i], 0.8f));
  dyn.frame(instances);
  for (uint32_t i = 0; i < meshes.size(); ++i) dyn.setPose(i, scrambled(meshes[i], 0.8f));
  dyn.frame(instances);
  CHECK(service->stats().rebuilds == expected);
}

namespace {

// Pose A at frame 0, pose B at frame 1, no update at frame 2: what each frame's TLAS traces.
struct LateScenario {
  rbsamples::CpuMesh poseA = rbsamples::makeSphere(1.0f, 24, 12);
  rbsamples::CpuMesh poseB = withPositions(poseA, deformed(poseA, [](uint32_t, int axis, const float* p) {
                                             return p[axis] * 0.6f;  // 1.6 times the radius
                                           }));
  rbsamples::CpuMesh ground = rbsamples::makeGrid(10.0f, 4);
  rb::PrimaryRayCamera camera = lookAt(0.0f, 3.5f, 7.0f, 0.0f, 1.2f, 0.0f);

  TestScene scene(const rbsamples::CpuMesh& pose) const {
    TestScene s;
    s.meshes = {pose, ground};
    s.instances = {{0, translation(-1.8f, 1.6f, 0)}, {0, translation(1.8f, 1.6f, 0)}, {1, translation(0, 0, 0)}};
    return s;
  }

  // Runs the three frames; `sameFrame` says which pose frame 1 must trace.
  void run(GpuFixture& fx, rb::AccelerationStructureService& service, bool late) {
    DynamicScene dyn(fx, service);
    const uint32_t m = dyn.add(poseA, "character");
    UploadedMesh groundUpload = fx.upload(ground);
    auto g = service.registerMesh(groundUpload.desc);
    RB_REQUIRE_OK(g);
    const TestScene layout = scene(poseA);
    std::vector<rb::Instance> instances;
    for (uint32_t i = 0; i < layout.instances.size(); ++i) {
      instances.push_back(
          instanceOf(layout.instances[i].mesh == 0 ? dyn.handle(m) : g.value(), layout.instances[i].transform, i));
    }
    rb::TlasInfo t0 = dyn.frame(instances);
    CHECK(t0.instanceCount == 3);  // the first frame has geometry, one frame late or not
    CHECK(service.stats().staleBlas == 0);

    dyn.setPose(m, poseB.positions);
    rb::TlasInfo t1 = dyn.frame(instances);
    CHECK(service.stats().staleBlas == (late ? 2u : 0u));
    {
      INFO("frame 1 traces pose " << (late ? "A" : "B"));
      checkDeformedTraceAgreement(compareFirstTrace(fx, scene(late ? poseA : poseB), t1.tlas, camera, 64, 48));
    }
    if (late) {
      rb::TlasInfo t2 = dyn.frame(instances);
      CHECK(service.stats().staleBlas == 0);
      INFO("frame 2 traces pose B");
      checkDeformedTraceAgreement(compareFirstTrace(fx, scene(poseB), t2.tlas, camera, 64, 48));
    }
    // An update every frame: one frame late always traces the pose before (no update is ever held back).
    rbsamples::CpuMesh previous = poseB, current = poseB;
    rb::TlasInfo t;
    for (uint32_t k = 1; k <= 4; ++k) {
      previous = current;
      current = withPositions(poseA, deformed(poseA, [](uint32_t v, int axis, const float* p) {
                                return axis == 1 ? 0.1f * std::sin(float(v)) : p[axis] * 0.3f;
                              }));
      for (float& c : current.positions) c *= 1.0f + 0.08f * float(k);
      dyn.setPose(m, current.positions);
      t = dyn.frame(instances);
      CHECK(service.stats().staleBlas == (late ? 2u : 0u));
      CHECK(service.stats().lastFrameRefitTriangles + service.stats().lastFrameRebuildTriangles ==
            poseA.triangleCount());
    }
    INFO("a run of updates traces the " << (late ? "previous" : "current") << " pose");
    checkDeformedTraceAgreement(compareFirstTrace(fx, scene(late ? previous : current), t.tlas, camera, 64, 48));
    fx.destroy(groundUpload);
  }
};

}  // namespace

TEST_CASE("one frame late traces the previous pose and says so; same frame traces this one", "[dynamic][late]") {
  GpuFixture fx;
  LateScenario scenario;
  VkDeviceSize lateBytes = 0, sameBytes = 0;
  {
    rb::AsServiceDesc desc;
    desc.dynamicMode = rb::DynamicBuildMode::AsyncOneFrameLate;  // no queue: the fallback
    desc.refitPolicy.maxRefitsBeforeRebuild = 2;                 // the chain of copies goes through rebuilds
    auto service = makeService(fx, desc);
    CHECK(!service->stats().async);
    scenario.run(fx, *service, true);
    CHECK(service->stats().rebuilds >= 1);
    lateBytes = service->stats().dynamicBlasBytes;
  }
  {
    rb::AsServiceDesc desc;
    desc.dynamicMode = rb::DynamicBuildMode::AsyncSameFrame;
    desc.refitPolicy.maxRefitsBeforeRebuild = 2;
    auto service = makeService(fx, desc);
    scenario.run(fx, *service, false);
    CHECK(service->stats().rebuilds >= 1);
    sameBytes = service->stats().dynamicBlasBytes;
    CHECK(fx.ctx().memoryStats().of(rb::MemoryCategory::BlasStorage) >= sameBytes);
  }
  // The late fallback keeps two copies (one traced while the next is written), same-frame one.
  CHECK(sameBytes > 0);
  CHECK(lateBytes == 2 * sameBytes);
}

TEST_CASE("without a second queue family the async modes report the fallback and work", "[dynamic][fallback]") {
  GpuFixture fx;
  {
    auto service = makeService(fx, {});
    CHECK(!service->stats().async);
    CHECK(service->stats().asyncFallbackReason.empty());  // InFrame asked for nothing else
    CHECK(service->stats().asyncQueueFamily == UINT32_MAX);
  }
  {
    rb::AsServiceDesc desc;
    desc.dynamicMode = rb::DynamicBuildMode::AsyncSameFrame;
    auto service = makeService(fx, desc);
    CHECK(!service->stats().async);
    CHECK(service->stats().asyncFallbackReason.find("asyncQueue is VK_NULL_HANDLE") != std::string::npos);
  }
  rb::AsServiceDesc desc;
  desc.dynamicMode = rb::DynamicBuildMode::AsyncOneFrameLate;
  desc.asyncQueue = fx.device().queue();  // lavapipe's only queue, of the main family
  desc.asyncQueueFamily = fx.device().queueFamily();
  auto service = makeService(fx, desc);
  rb::AsStats st = service->stats();
  CHECK(!st.async);
  INFO(st.asyncFallbackReason);
  CHECK(st.asyncFallbackReason.find("main queue family") != std::string::npos);
  // The waits are the engine's own queue order: none is handed out, and `out` is left alone.
  VkSemaphoreSubmitInfo untouched{VK_STRUCTURE_TYPE_SEMAPHORE_SUBMIT_INFO};
  untouched.value = 12345;
  CHECK(!service->fillTlasWait(untouched));
  CHECK(!service->fillVertexReuseWait(untouched));
  CHECK(untouched.value == 12345);
  // ... and the work happens in recordPendingWork.
  DynamicScene dyn(fx, *service);
  const rbsamples::CpuMesh grid = rbsamples::makeGrid(2.0f, 4);
  const uint32_t m = dyn.add(grid);
  const std::vector<rb::Instance> instances = {instanceOf(dyn.handle(m), translation(0, 0, 0), 0)};
  CHECK(dyn.frame(instances).instanceCount == 1);
  dyn.setPose(m, ripple(grid, 1.0f));
  dyn.frame(instances);
  CHECK(service->stats().refits == 1);
  CHECK(!service->fillTlasWait(untouched));

  SECTION("descriptions the SDK cannot use are refused, naming the value") {
    rb::AsServiceDesc bad = desc;
    bad.asyncQueueFamily = 99;
    auto b = rb::AccelerationStructureService::create(fx.ctx(), bad);
    REQUIRE(!b.ok());
    CHECK(b.error().code == rb::ErrorCode::InvalidArgument);
    CHECK(b.error().message.find("asyncQueueFamily 99") != std::string::npos);
    rb::AsServiceDesc growth;
    growth.refitPolicy.maxAreaGrowth = 0.5f;
    auto g = rb::AccelerationStructureService::create(fx.ctx(), growth);
    REQUIRE(!g.ok());
    CHECK(g.error().message.find("maxAreaGrowth is 0.5") != std::string::npos);
  }
}

TEST_CASE("updateMesh with new counts needs forceRebuild, then traces the new mesh", "[dynamic][embree]") {
  GpuFixture fx;
  auto service = makeService(fx, {});
  DynamicScene dyn(fx, *service);
  const rbsamples::CpuMesh small = rbsamples::makeGrid(3.0f, 8);              // 81 vertices, 128 triangles
  const rbsamples::CpuMesh large = rbsamples::makeBumpyGrid(3.0f, 12, 0.4f);  // 169 vertices, 288 triangles
  const uint32_t m = dyn.add(small, "cloth");
  const std::vector<rb::Instance> instances = {instanceOf(dyn.handle(m), translation(0, 0, 0), 0)};
  dyn.frame(instances);

  rb::Status refused = dyn.replace(m, large, false);
  REQUIRE(!refused.ok());
  CHECK(refused.error().code == rb::ErrorCode::InvalidArgument);
  INFO(refused.error().message);
  CHECK(refused.error().message.find("mesh 'cloth'") != std::string::npos);
  CHECK(refused.error().message.find("vertexCount 81 -> 169") != std::string::npos);
  CHECK(refused.error().message.find("triangleCount 128 -> 288") != std::string::npos);
  CHECK(refused.error().message.find("forceRebuild") != std::string::npos);
  CHECK(service->stats().refits + service->stats().rebuilds == 0);  // nothing changed

  RB_REQUIRE_OK(dyn.replace(m, large, true));
  rb::TlasInfo tlas = dyn.frame(instances);
  CHECK(service->stats().rebuilds == 1);
  CHECK(service->stats().triangles == large.triangleCount());
  TestScene scene;
  scene.meshes = {large};
  scene.instances = {{0, translation(0, 0, 0)}};
  const rb::PrimaryRayCamera cam = lookAt(0.4f, 3.5f, 2.5f, 0, 0, 0);
  checkDeformedTraceAgreement(compareFirstTrace(fx, scene, tlas.tlas, cam, 64, 64));

  // New buffers with the same counts: refit from them, no rebuild needed.
  const rbsamples::CpuMesh lifted =
      withPositions(large, deformed(large, [](uint32_t, int axis, const float*) { return axis == 1 ? 0.5f : 0.0f; }));
  RB_REQUIRE_OK(dyn.replace(m, lifted, false));
  tlas = dyn.frame(instances);
  CHECK(service->stats().refits == 1);
  CHECK(service->stats().rebuilds == 1);
  scene.meshes = {lifted};
  checkDeformedTraceAgreement(compareFirstTrace(fx, scene, tlas.tlas, cam, 64, 64));
}
