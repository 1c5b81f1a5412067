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
  uint32_t material = 0;
};

struct TestScene {
  std::vector<rbsamples::CpuMesh> meshes;
  std::vector<SceneInstance> instances;
};

// A bumpy ground, spheres, boxes and a rotated, scaled box: smooth and flat surfaces, grazing angles,
// shared meshes between instances.
TestScene makeConformanceScene();
// The camera the conformance tests look at that scene with (vertical field of view: 0 = the pass default).
rb::PrimaryRayCamera conformanceCamera(float verticalFovDegrees = 0.0f);
std::array<float, 12> translation(float x, float y, float z);

// The scene registered with a service and its TLAS built (in one submitted frame).
struct BuiltScene {
  std::vector<UploadedMesh> uploads;
  std::vector<rb::MeshHandle> handles;
  std::vector<rb::Instance> instances;
  rb::TlasInfo tlas;
};
// Options of a TLAS built without ALLOW_UPDATE (the default mode refits), so a test's first refitting build
// must rebuild.
inline const rb::TlasBuildOptions kRebuildTlas{.mode = rb::TlasBuildMode::Rebuild};

// Uploads and registers the meshes, builds them and a TLAS over the instances with `options`.
BuiltScene buildScene(GpuFixture& fx, rb::AccelerationStructureService& service, const TestScene& scene,
                      const rb::TlasBuildOptions& options = {});
void destroyScene(GpuFixture& fx, BuiltScene& built);
void addToEmbree(EmbreeScene& embree, const TestScene& scene);

struct PixelRay {
  float origin[3];
  float dir[3];
};
// The same ray the primary raygen shader builds (see PrimaryRayCamera), for pixel coordinates that may be
// fractional (the pixel centre is x + 0.5).
PixelRay rayThrough(const rb::CameraBasis& b, float px, float py, uint32_t w, uint32_t h);

// Traces the scene's TLAS with the first-trace pass and compares every pixel away from silhouettes with
// Embree tracing the same rays.
struct TraceComparison {
  uint32_t compared = 0, silhouettes = 0, hits = 0;
  uint32_t hitMissAgree = 0, hitsCompared = 0, distanceAgree = 0, sameInstance = 0, missIdsCorrect = 0, misses = 0;
};
TraceComparison compareFirstTrace(GpuFixture& fx, const TestScene& scene, VkAccelerationStructureKHR tlas,
                                  const rb::PrimaryRayCamera& camera, uint32_t width, uint32_t height);

}  // namespace rbtest
