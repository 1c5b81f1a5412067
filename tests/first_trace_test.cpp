// The first trace agrees with an independent tracer (Embree) on hit/miss, hit distance and what was hit.
#include <catch2/catch_test_macros.hpp>


#include "test_scene.h"

using namespace rbtest;

TEST_CASE("first trace matches Embree on a procedural scene", "[trace][embree]") {
  GpuFixture fx;
  auto service = rb::AccelerationStructureService::create(fx.ctx());
  RB_REQUIRE_OK(service);
  TestScene scene = makeConformanceScene();
  BuiltScene built = buildScene(fx, *service.value(), scene);

  const rb::PrimaryRayCamera cam = conformanceCamera(50.0f);
  const uint32_t W = 192, H = 128;
  TraceComparison c = compareFirstTrace(fx, scene, built.tlas.tlas, cam, W, H);
  INFO("compared " << c.compared << " pixels (" << c.silhouettes << " near silhouettes excluded), " << c.hits
                   << " hits");
  REQUIRE(c.compared > W * H * 3 / 4);
  REQUIRE(c.hits > c.compared / 2);    // the view is mostly geometry,
  REQUIRE(c.compared - c.hits > 100);  // with some sky
  CHECK(double(c.hitMissAgree) / c.compared >= 0.999);
  CHECK(double(c.distanceAgree) / c.hitsCompared >= 0.999);
  CHECK(double(c.sameInstance) / c.hitsCompared >= 0.999);
  CHECK(c.missIdsCorrect == c.misses);
  destroyScene(fx, built);
}
