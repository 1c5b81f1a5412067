// Content-hash dedup: identical geometry shares one BLAS, different geometry does not.
#include <catch2/catch_test_macros.hpp>

#include <algorithm>

#include "test_scene.h"

using namespace rbtest;

TEST_CASE("identical geometry registered twice shares one BLAS", "[as][dedup]") {
  GpuFixture fx;
  auto service = rb::AccelerationStructureService::create(fx.ctx());
  RB_REQUIRE_OK(service);
  auto& s = *service.value();

  rbsamples::CpuMesh sphere = rbsamples::makeSphere(1.0f, 16, 8);
  // Two uploads of the same data into different engine buffers: only the content hash can match them.
  UploadedMesh a = fx.upload(sphere), b = fx.upload(sphere);
  REQUIRE(a.desc.vertexAddress != b.desc.vertexAddress);
  auto ha = s.registerMesh(a.desc);
  auto hb = s.registerMesh(b.desc);
  RB_REQUIRE_OK(ha);
  RB_REQUIRE_OK(hb);
  CHECK(!(ha.value() == hb.value()));  // each registration has its own handle and lifetime
  rb::AsStats st = s.stats();
  CHECK(st.blasCount == 1);
  CHECK(st.dedupHits == 1);
  CHECK(st.registrations == 2);

  SECTION("different geometry gives a second BLAS") {
    rbsamples::CpuMesh other = sphere;
    other.positions[0] += 0.25f;  // one coordinate differs
    UploadedMesh c = fx.upload(other);
    auto hc = s.registerMesh(c.desc);
    RB_REQUIRE_OK(hc);
    CHECK(s.stats().blasCount == 2);
    fx.runAndSettle([&](VkCommandBuffer cmd) { RB_REQUIRE_OK(s.recordPendingWork(cmd)); });
    CHECK(s.stats().blasCount == 2);
    // One BLAS for the two identical registrations, another for the different one.
    CHECK(s.blasAddress(ha.value()).value() == s.blasAddress(hb.value()).value());
    CHECK(s.blasAddress(hc.value()).value() != s.blasAddress(ha.value()).value());
    fx.destroy(c);
  }

  SECTION("the shared BLAS lives until its last registration is released, and builds from live buffers") {
    RB_REQUIRE_OK(s.releaseMesh(ha.value()));
    CHECK(!s.isBuilt(ha.value()).ok());  // that handle is gone
    CHECK(s.isBuilt(hb.value()).ok());   // the other registration keeps the BLAS
    // The first registration's buffers may be reused now: zero its vertices (host-visible copy) — the queued
    // build must read the second registration's buffers and still produce the sphere.
    fx.destroy(a);
    rbsamples::CpuMesh zeros = sphere;
    std::fill(zeros.positions.begin(), zeros.positions.end(), 0.0f);
    auto reused = fx.device().createBuffer(sphere.positions.size() * sizeof(float),
                                           VK_BUFFER_USAGE_SHADER_DEVICE_ADDRESS_BIT |
                                               VK_BUFFER_USAGE_ACCELERATION_STRUCTURE_BUILD_INPUT_READ_ONLY_BIT_KHR,
                                           true, zeros.positions.data());
    RB_REQUIRE_OK(reused);
    rb::Instance inst;
    inst.mesh = hb.value();
    rb::TlasInfo tlas;
    fx.runFrame([&](VkCommandBuffer cmd) {
      RB_REQUIRE_OK(s.recordPendingWork(cmd));
      tlas = s.recordTlasBuild(cmd, std::span(&inst, 1)).value();
    });
    CHECK(s.isBuilt(hb.value()).value());
    TestScene scene;
    scene.meshes.push_back(sphere);
    scene.instances.push_back({0, translation(0, 0, 0)});
    rb::PrimaryRayCamera cam;
    cam.eye[2] = 4.0f;
    cam.target[2] = 0.0f;
    TraceComparison c = compareFirstTrace(fx, scene, tlas.tlas, cam, 48, 48);
    CHECK(c.hitsCompared > 200);
    CHECK(c.distanceAgree == c.hitsCompared);
    fx.device().destroyBuffer(reused.value());
    RB_REQUIRE_OK(s.releaseMesh(hb.value()));
    auto again = s.isBuilt(hb.value());
    REQUIRE(!again.ok());
    CHECK(again.error().code == rb::ErrorCode::StaleHandle);
    CHECK(s.stats().meshHandles == 0);
  }

  SECTION("an engine-supplied key dedups without host data") {
    UploadedMesh c = fx.upload(sphere, /*withHostCopies=*/false);
    UploadedMesh d = fx.upload(sphere, false);
    c.desc.contentKey = d.desc.contentKey = 0xC0FFEE;
    auto hc = s.registerMesh(c.desc), hd = s.registerMesh(d.desc);
    RB_REQUIRE_OK(hc);
    RB_REQUIRE_OK(hd);
    CHECK(s.stats().blasCount == 2);  // c and d share one, a and b the other
    CHECK(s.stats().dedupHits == 2);
    fx.destroy(c);
    fx.destroy(d);
  }

  SECTION("without host data or key, only the same buffer range dedups") {
    UploadedMesh c = fx.upload(sphere, false);
    auto h1 = s.registerMesh(c.desc), h2 = s.registerMesh(c.desc);
    UploadedMesh d = fx.upload(sphere, false);
    auto h3 = s.registerMesh(d.desc);
    RB_REQUIRE_OK(h1);
    RB_REQUIRE_OK(h2);
    RB_REQUIRE_OK(h3);
    CHECK(s.stats().blasCount == 3);  // h1 and h2 share, h3 (other buffers, no host data) does not
    CHECK(s.stats().dedupHits == 2);
    fx.destroy(c);
    fx.destroy(d);
  }

  SECTION("dynamic meshes are never merged by content") {
    a.desc.role = rb::MeshRole::Dynamic;
    b.desc.role = rb::MeshRole::Dynamic;
    auto d1 = s.registerMesh(a.desc), d2 = s.registerMesh(b.desc);
    RB_REQUIRE_OK(d1);
    RB_REQUIRE_OK(d2);
    CHECK(s.stats().blasCount == 3);  // the shared static one, and one per dynamic registration
  }

  SECTION("instances of one mesh share its BLAS in the TLAS") {
    std::vector<rb::Instance> instances(3);
    for (int i = 0; i < 3; ++i) {
      instances[i].mesh = ha.value();
      instances[i].transform[3] = float(i) * 3.0f;
    }
    rb::TlasInfo info;
    fx.runFrame([&](VkCommandBuffer cmd) {
      RB_REQUIRE_OK(s.recordPendingWork(cmd));
      auto t = s.recordTlasBuild(cmd, instances);
      RB_REQUIRE_OK(t);
      info = t.value();
    });
    CHECK(info.instanceCount == 3);
    CHECK(s.stats().blasCount == 1);
  }
  fx.destroy(a);  // a no-op where a section destroyed it already
  fx.destroy(b);
}
