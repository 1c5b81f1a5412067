// Content-hash dedup: identical geometry shares one BLAS, different geometry does not.
#include <catch2/catch_test_macros.hpp>

#include "test_support.h"

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
  CHECK(ha.value() == hb.value());
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
    CHECK(!(hc.value() == ha.value()));
    CHECK(s.stats().blasCount == 2);
    fx.runAndSettle([&](VkCommandBuffer cmd) { RB_REQUIRE_OK(s.recordPendingWork(cmd)); });
    CHECK(s.stats().blasCount == 2);
    fx.destroy(c);
  }

  SECTION("the shared BLAS lives until its last reference is released") {
    RB_REQUIRE_OK(s.releaseMesh(ha.value()));
    CHECK(s.isBuilt(hb.value()).ok());  // still referenced once
    RB_REQUIRE_OK(s.releaseMesh(hb.value()));
    auto again = s.isBuilt(hb.value());
    REQUIRE(!again.ok());
    CHECK(again.error().code == rb::ErrorCode::StaleHandle);
  }

  SECTION("an engine-supplied key dedups without host data") {
    UploadedMesh c = fx.upload(sphere, /*withHostCopies=*/false);
    UploadedMesh d = fx.upload(sphere, false);
    c.desc.contentKey = d.desc.contentKey = 0xC0FFEE;
    auto hc = s.registerMesh(c.desc), hd = s.registerMesh(d.desc);
    RB_REQUIRE_OK(hc);
    RB_REQUIRE_OK(hd);
    CHECK(hc.value() == hd.value());
    CHECK(!(hc.value() == ha.value()));
    CHECK(s.stats().blasCount == 2);
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
    CHECK(h1.value() == h2.value());
    CHECK(!(h1.value() == h3.value()));
    fx.destroy(c);
    fx.destroy(d);
  }

  SECTION("dynamic meshes are never merged by content") {
    a.desc.role = rb::MeshRole::Dynamic;
    b.desc.role = rb::MeshRole::Dynamic;
    auto d1 = s.registerMesh(a.desc), d2 = s.registerMesh(b.desc);
    RB_REQUIRE_OK(d1);
    RB_REQUIRE_OK(d2);
    CHECK(!(d1.value() == d2.value()));
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
  fx.destroy(a);
  fx.destroy(b);
}
