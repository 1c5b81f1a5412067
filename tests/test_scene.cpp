#include "test_scene.h"

#include <cmath>

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

BuiltScene buildScene(GpuFixture& fx, rb::AccelerationStructureService& service, const TestScene& scene) {
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
    b.instances.push_back(inst);
  }
  fx.runFrame([&](VkCommandBuffer cmd) {
    auto pending = service.recordPendingWork(cmd);
    RB_REQUIRE_OK(pending);
    REQUIRE(pending.value() == 0);
    auto tlas = service.recordTlasBuild(cmd, b.instances);
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

}  // namespace rbtest
