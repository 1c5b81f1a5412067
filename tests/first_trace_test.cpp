// The first trace agrees with an independent tracer (Embree) on hit/miss, hit distance and what was hit.
#include <catch2/catch_test_macros.hpp>

#include <cmath>
#include <cstring>

#include "test_scene.h"

using namespace rbtest;

namespace {

struct PixelRay {
  float origin[3];
  float dir[3];
};

// The same ray the raygen shader builds (see PrimaryRayCamera), for pixel coordinates that may be fractional.
PixelRay rayThrough(const rb::CameraBasis& b, float px, float py, uint32_t w, uint32_t h) {
  float nx = px / float(w) * 2.0f - 1.0f, ny = py / float(h) * 2.0f - 1.0f;
  PixelRay r;
  float len2 = 0;
  for (int i = 0; i < 3; ++i) {
    r.origin[i] = b.eye[i];
    r.dir[i] = b.forward[i] + nx * b.right[i] - ny * b.up[i];
    len2 += r.dir[i] * r.dir[i];
  }
  for (float& d : r.dir) d /= std::sqrt(len2);
  return r;
}

}  // namespace

TEST_CASE("first trace matches Embree on a procedural scene", "[trace][embree]") {
  GpuFixture fx;
  auto service = rb::AccelerationStructureService::create(fx.ctx());
  RB_REQUIRE_OK(service);
  TestScene scene = makeConformanceScene();
  BuiltScene built = buildScene(fx, *service.value(), scene);
  auto pass = rb::PrimaryRayPass::create(fx.ctx());
  RB_REQUIRE_OK(pass);

  const uint32_t W = 192, H = 128;
  rb::PrimaryRayCamera cam;
  float eye[3] = {-9.0f, 4.5f, 11.0f}, target[3] = {0.5f, 0.8f, -0.5f};
  std::memcpy(cam.eye, eye, sizeof eye);
  std::memcpy(cam.target, target, sizeof target);
  cam.verticalFovDegrees = 50.0f;
  rb::GpuImage dist = fx.makeImage(W, H, VK_FORMAT_R32_SFLOAT);
  rb::GpuImage ids = fx.makeImage(W, H, VK_FORMAT_R32G32_UINT);
  fx.runFrame([&](VkCommandBuffer cmd) {
    fx.toGeneral(cmd, dist);
    fx.toGeneral(cmd, ids);
    RB_REQUIRE_OK(pass.value()->record(cmd, built.tlas.tlas, cam, {dist.view, ids.view, W, H}));
  });
  std::vector<uint8_t> distBytes = fx.readImage(dist, 4), idBytes = fx.readImage(ids, 8);
  const float* gpuT = reinterpret_cast<const float*>(distBytes.data());
  const uint32_t* gpuIds = reinterpret_cast<const uint32_t*>(idBytes.data());

  EmbreeScene embree;
  addToEmbree(embree, scene);
  auto basis = rb::computeCameraBasis(cam, W, H);
  RB_REQUIRE_OK(basis);

  uint32_t compared = 0, hitMissAgree = 0, distanceAgree = 0, hitsCompared = 0, silhouettes = 0, hits = 0;
  uint32_t sameInstance = 0;
  for (uint32_t y = 0; y < H; ++y) {
    for (uint32_t x = 0; x < W; ++x) {
      PixelRay r = rayThrough(basis.value(), x + 0.5f, y + 0.5f, W, H);
      ReferenceHit ref = embree.intersect(r.origin, r.dir, 0.0f, 1e30f);
      // Exclude rays within one pixel of a silhouette: any ray offset by up to one pixel sees a different object,
      // a different hit/miss outcome, or a depth discontinuity.
      bool silhouette = false;
      for (int dy = -1; dy <= 1 && !silhouette; ++dy) {
        for (int dx = -1; dx <= 1 && !silhouette; ++dx) {
          if (!dx && !dy) continue;
          PixelRay n = rayThrough(basis.value(), x + 0.5f + dx, y + 0.5f + dy, W, H);
          ReferenceHit nh = embree.intersect(n.origin, n.dir, 0.0f, 1e30f);
          silhouette = nh.hit != ref.hit || (ref.hit && (nh.instanceId != ref.instanceId ||
                                                         std::fabs(nh.t - ref.t) > 0.2f * ref.t));
        }
      }
      if (silhouette) {
        ++silhouettes;
        continue;
      }
      ++compared;
      size_t p = size_t(y) * W + x;
      bool gpuHit = gpuT[p] > 0.0f;
      if (gpuHit == ref.hit) ++hitMissAgree;
      if (ref.hit) ++hits;
      if (gpuHit && ref.hit) {
        ++hitsCompared;
        if (std::fabs(gpuT[p] - ref.t) <= 1e-4f * ref.t) ++distanceAgree;
        if (gpuIds[2 * p + 1] == ref.instanceId) ++sameInstance;
      } else if (!gpuHit) {
        CHECK(gpuIds[2 * p] == 0xFFFFFFFFu);
      }
    }
  }
  INFO("compared " << compared << " pixels (" << silhouettes << " near silhouettes excluded), " << hits << " hits");
  REQUIRE(compared > W * H * 3 / 4);
  REQUIRE(hits > compared / 2);  // the view is mostly geometry, not sky
  REQUIRE(compared - hits > 100);  // and some sky
  CHECK(double(hitMissAgree) / compared >= 0.999);
  CHECK(double(distanceAgree) / hitsCompared >= 0.999);
  CHECK(double(sameInstance) / hitsCompared >= 0.999);

  fx.destroyImage(dist);
  fx.destroyImage(ids);
  destroyScene(fx, built);
}
