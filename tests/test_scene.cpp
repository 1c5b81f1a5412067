#include "test_scene.h"

#include <cmath>
#include <cstring>

namespace rbtest {

std::array<float, 12> translation(float x, float y, float z) { return {1, 0, 0, x, 0, 1, 0, y, 0, 0, 1, z}; }

TestScene makeConformanceScene() {
  TestScene s;
  s.meshes.push_back(rbsamples::makeBumpyGrid(40.0f, 96, 0.3f));  // 0: ground
  s.meshes.push_back(rbsamples::makeSphere(1.0f, 48, 24));        // 1: sphere
  const float mn[3] = {-1, -1, -1}, mx[3] = {1, 1, 1};
  s.meshes.push_back(rbsamples::makeBox(mn, mx, 2));  // 2: box
  s.instances.push_back({0, translation(0, 0, 0)});
  s.instances.push_back({1, translation(-3, 1.5f, 0)});
  s.instances.push_back({1, translation(2.5f, 1.2f, -3)});
  s.instances.push_back({2, translation(0, 1.0f, 2)});
  // Rotated 30 degrees about Y and scaled: exercises non-trivial instance transforms.
  float c = std::cos(0.5236f), sn = std::sin(0.5236f);
  s.instances.push_back({2, {1.5f * c, 0, 1.5f * sn, 4, 0, 0.5f, 0, 0.6f, -1.5f * sn, 0, 1.5f * c, 1}});
  return s;
}

rb::PrimaryRayCamera conformanceCamera(float verticalFovDegrees) {
  rb::PrimaryRayCamera cam;
  const float eye[3] = {-9.0f, 4.5f, 11.0f}, target[3] = {0.5f, 0.8f, -0.5f};
  std::memcpy(cam.eye, eye, sizeof eye);
  std::memcpy(cam.target, target, sizeof target);
  cam.verticalFovDegrees = verticalFovDegrees;
  return cam;
}

BuiltScene buildScene(GpuFixture& fx, rb::AccelerationStructureService& service, const TestScene& scene,
                      const rb::TlasBuildOptions& options) {
  BuiltScene b;
  for (const rbsamples::CpuMesh& m : scene.meshes) {
    b.uploads.push_back(fx.upload(m));
    auto h = service.registerMesh(b.uploads.back().desc);
    RB_REQUIRE_OK(h);
    b.handles.push_back(h.value());
  }
  for (uint32_t i = 0; i < scene.instances.size(); ++i) {
    rb::Instance inst;
    inst.mesh = b.handles[scene.instances[i].mesh];
    std::copy(scene.instances[i].transform.begin(), scene.instances[i].transform.end(), inst.transform);
    inst.customIndex = i;
    inst.material = scene.instances[i].material;
    b.instances.push_back(inst);
  }
  fx.runFrame([&](VkCommandBuffer cmd) {
    auto pending = service.recordPendingWork(cmd);
    RB_REQUIRE_OK(pending);
    REQUIRE(pending.value() == 0);
    auto tlas = service.recordTlasBuild(cmd, b.instances, options);
    RB_REQUIRE_OK(tlas);
    b.tlas = tlas.value();
  });
  REQUIRE(b.tlas.skippedInstances == 0);
  return b;
}

void destroyScene(GpuFixture& fx, BuiltScene& built) {
  for (UploadedMesh& m : built.uploads) fx.destroy(m);
  built.uploads.clear();
}

void addToEmbree(EmbreeScene& embree, const TestScene& scene) {
  for (uint32_t i = 0; i < scene.instances.size(); ++i) {
    embree.addInstance(scene.meshes[scene.instances[i].mesh], scene.instances[i].transform.data(), i);
  }
  embree.commit();
}

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

TraceComparison compareFirstTrace(GpuFixture& fx, const TestScene& scene, VkAccelerationStructureKHR tlas,
                                  const rb::PrimaryRayCamera& cam, uint32_t W, uint32_t H) {
  auto pass = rb::PrimaryRayPass::create(fx.ctx());
  RB_REQUIRE_OK(pass);
  rb::GpuImage dist = fx.makeImage(W, H, VK_FORMAT_R32_SFLOAT);
  rb::GpuImage ids = fx.makeImage(W, H, VK_FORMAT_R32G32_UINT);
  fx.runFrame([&](VkCommandBuffer cmd) {
    fx.toGeneral(cmd, dist);
    fx.toGeneral(cmd, ids);
    RB_REQUIRE_OK(pass.value()->record(
        cmd, {.tlas = rb::TlasInfo{.tlas = tlas}, .camera = cam, .targets = {dist.view, ids.view, W, H}}));
  });
  std::vector<uint8_t> distBytes = fx.readImage(dist, 4), idBytes = fx.readImage(ids, 8);
  fx.destroyImage(dist);
  fx.destroyImage(ids);
  const float* gpuT = reinterpret_cast<const float*>(distBytes.data());
  const uint32_t* gpuIds = reinterpret_cast<const uint32_t*>(idBytes.data());

  EmbreeScene embree;
  addToEmbree(embree, scene);
  auto basis = rb::computeCameraBasis(cam, W, H);
  RB_REQUIRE_OK(basis);
  TraceComparison c;
  for (uint32_t y = 0; y < H; ++y) {
    for (uint32_t x = 0; x < W; ++x) {
      PixelRay r = rayThrough(basis.value(), x + 0.5f, y + 0.5f, W, H);
      ReferenceHit ref = embree.intersect(r.origin, r.dir, 0.0f, 1e30f);
      // A ray within one pixel of a silhouette: a ray offset by up to one pixel sees another object, another
      // hit/miss outcome, or a depth discontinuity.
      bool silhouette = false;
      for (int dy = -1; dy <= 1 && !silhouette; ++dy) {
        for (int dx = -1; dx <= 1 && !silhouette; ++dx) {
          if (!dx && !dy) continue;
          PixelRay n = rayThrough(basis.value(), x + 0.5f + dx, y + 0.5f + dy, W, H);
          ReferenceHit nh = embree.intersect(n.origin, n.dir, 0.0f, 1e30f);
          silhouette = nh.hit != ref.hit ||
                       (ref.hit && (nh.instanceId != ref.instanceId || std::fabs(nh.t - ref.t) > 0.2f * ref.t));
        }
      }
      if (silhouette) {
        ++c.silhouettes;
        continue;
      }
      ++c.compared;
      size_t p = size_t(y) * W + x;
      bool gpuHit = gpuT[p] > 0.0f;
      if (gpuHit == ref.hit) ++c.hitMissAgree;
      if (ref.hit) ++c.hits;
      if (gpuHit && ref.hit) {
        ++c.hitsCompared;
        if (std::fabs(gpuT[p] - ref.t) <= 1e-4f * ref.t) ++c.distanceAgree;
        if (gpuIds[2 * p + 1] == ref.instanceId) ++c.sameInstance;
      } else if (!gpuHit) {
        ++c.misses;
        if (gpuIds[2 * p] == 0xFFFFFFFFu && gpuIds[2 * p + 1] == 0xFFFFFFFFu) ++c.missIdsCorrect;
      }
    }
  }
  return c;
}

}  // namespace rbtest
