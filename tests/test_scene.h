// A small procedural scene for conformance tests, traced by Raybridge and by the Embree reference alike.
#pragma once

#include <raybridge/raybridge.h>

#include <array>
#include <vector>

#include "embree_reference.h"
#include "procedural_meshes.h"
#include "test_support.h"

namespace rbtest {

struct SceneInstance {
  uint32_t mesh;
  std::array<float, 12> transform;
};

struct TestScene {
  std::vector<rbsamples::CpuMesh> meshes;
  std::vector<SceneInstance> instances;
};

// A bumpy ground, spheres, boxes and a rotated, scaled box: smooth and flat surfaces, grazing angles,
// shared meshes between instances.
TestScene makeConformanceScene();
std::array<float, 12> translation(float x, float y, float z);

// The scene registered with a service and its TLAS built (in one submitted frame).
struct BuiltScene {
  std::vector<UploadedMesh> uploads;
  std::vector<rb::MeshHandle> handles;
  std::vector<rb::Instance> instances;
  rb::TlasInfo tlas;
};
BuiltScene buildScene(GpuFixture& fx, rb::AccelerationStructureService& service, const TestScene& scene);
void destroyScene(GpuFixture& fx, BuiltScene& built);
void addToEmbree(EmbreeScene& embree, const TestScene& scene);

}  // namespace rbtest
