// The PrimaryShadingPass (pure ray tracing): its distances are Embree's primary hits, a miss returns the sky, hits
// are lit, its own and a caller's radiance image both work, and bad input is named before anything is recorded.
#include <catch2/catch_test_macros.hpp>

#include <cmath>
#include <string>

#include "synthetic_gbuffer.h"

using namespace rbtest;

namespace {

bool contains(const std::string& text, const char* part) { return text.find(part) != std::string::npos; }

struct ShadingRun {
  std::vector<float> distance, radiance;  // radiance: RGBA per pixel
  rb::PassStats stats;
};

// One frame of the pass over the conformance scene from its camera, camera-relative TLAS with shading records.
ShadingRun runShading(GpuFixture& fx, const TestScene& scene, const rb::PrimaryRayCamera& camera, uint32_t W,
                      uint32_t H, const rb::PrimaryShadingSettings& settings) {
  auto service = rb::AccelerationStructureService::create(fx.ctx());
  RB_REQUIRE_OK(service);
  rb::TlasBuildOptions options;
  for (int i = 0; i < 3; ++i) options.originOffset[i] = camera.eye[i];
  options.writeShadingRecords = true;
  BuiltScene built = buildScene(fx, *service.value(), scene, options);
  auto pass = rb::PrimaryShadingPass::create(fx.ctx());
  RB_REQUIRE_OK(pass);
  fx.runFrame([&](VkCommandBuffer cmd) {
    RB_REQUIRE_OK(pass.value()->record(
        cmd, {.tlas = built.tlas, .camera = camera, .targets = {W, H, VK_NULL_HANDLE}, .settings = settings}));
  });
  const rb::PrimaryShadingOutputs& o = pass.value()->outputs();
  REQUIRE(o.radiance != VK_NULL_HANDLE);
  REQUIRE(o.distance != VK_NULL_HANDLE);
  ShadingRun run;
  run.distance = readR32f(fx, o.distance, W, H);
  run.radiance = readRgba16f(fx, o.radiance, W, H);
  for (uint32_t i = 0; i < fx.ctx().framesInFlight(); ++i) fx.ctx().beginFrame();
  (void)fx.device().waitIdle();
  run.stats = pass.value()->stats();
  destroyScene(fx, built);
  return run;
}

}  // namespace

TEST_CASE("primary shading: distances match Embree, misses see the sky, hits are lit", "[primary-shading][embree]") {
  GpuFixture fx;
  const uint32_t W = 96, H = 64;
  TestScene scene = makeConformanceScene();
  const rb::PrimaryRayCamera camera = conformanceCamera();
  rb::PrimaryShadingSettings settings;  // zero: the default sun, sky and ambient; every surface white
  settings.lighting.sunDirection[0] = 0.3f, settings.lighting.sunDirection[1] = 1.0f,
  settings.lighting.sunDirection[2] = 0.2f;
  ShadingRun run = runShading(fx, scene, camera, W, H, settings);

  EmbreeScene embree;
  addToEmbree(embree, scene);
  auto basis = rb::computeCameraBasis(camera, W, H);
  RB_REQUIRE_OK(basis);
  uint32_t compared = 0, agree = 0, misses = 0, skyCorrect = 0, hits = 0, lit = 0;
  for (uint32_t y = 1; y + 1 < H; ++y) {
    for (uint32_t x = 1; x + 1 < W; ++x) {
      PixelRay r = rayThrough(basis.value(), x + 0.5f, y + 0.5f, W, H);
      ReferenceHit ref = embree.intersect(r.origin, r.dir, 0.0f, 1e30f);
      bool silhouette = false;
      for (int dy = -1; dy <= 1; ++dy) {
        for (int dx = -1; dx <= 1; ++dx) {
          PixelRay n = rayThrough(basis.value(), x + 0.5f + dx, y + 0.5f + dy, W, H);
          ReferenceHit nh = embree.intersect(n.origin, n.dir, 0.0f, 1e30f);
          silhouette |= nh.hit != ref.hit ||
                        (ref.hit && (nh.instanceId != ref.instanceId || std::fabs(nh.t - ref.t) > 0.2f * ref.t));
        }
      }
      if (silhouette) continue;
      const size_t p = size_t(y) * W + x;
      const float* rgb = &run.radiance[4 * p];
      ++compared;
      if (!ref.hit) {
        ++misses;
        bool sky = run.distance[p] == 0.0f;
        for (int c = 0; c < 3; ++c) sky &= std::fabs(rgb[c] - rb::kDefaultSkyRadiance[c]) <= 2e-3f;
        skyCorrect += sky;
        continue;
      }
      ++hits;
      agree += std::fabs(run.distance[p] - ref.t) <= 1e-4f * ref.t;
      // At least the white surface's sky light (ambient 0.4 times the sky), more where the sun reaches it.
      lit += rgb[0] >= 0.4f * rb::kDefaultSkyRadiance[0] - 1e-3f && rgb[2] >= 0.4f * rb::kDefaultSkyRadiance[2] - 1e-3f;
    }
  }
  INFO("compared " << compared << ": hits " << hits << " (distance agrees " << agree << ", lit " << lit << "), misses "
                   << misses << " (sky " << skyCorrect << ")");
  REQUIRE(hits > compared / 3);
  REQUIRE(misses > 0);
  CHECK(agree == hits);
  CHECK(skyCorrect == misses);
  CHECK(lit == hits);
  // One primary ray per pixel plus a shadow ray from every hit that faces the sun.
  CHECK(run.stats.rays > uint64_t(W) * H);
  CHECK(run.stats.rays < 2 * uint64_t(W) * H);
  CHECK(run.stats.gpuMs > 0.0);
}

TEST_CASE("primary shading rejects bad input with a message naming it", "[primary-shading][bad-input]") {
  GpuFixture fx;
  TestScene scene = makeConformanceScene();
  auto service = rb::AccelerationStructureService::create(fx.ctx());
  RB_REQUIRE_OK(service);
  rb::TlasBuildOptions options;
  options.writeShadingRecords = true;
  BuiltScene built = buildScene(fx, *service.value(), scene, options);
  auto pass = rb::PrimaryShadingPass::create(fx.ctx());
  RB_REQUIRE_OK(pass);
  const rb::PrimaryRayCamera camera = conformanceCamera();
  rb::TlasInfo noRecords = built.tlas;
  noRecords.shadingRecords = VK_NULL_HANDLE;
  fx.runFrame([&](VkCommandBuffer cmd) {
    auto expect = [&](const rb::Status& s, const char* part) {
      REQUIRE_FALSE(s.ok());
      INFO(s.error().message);
      CHECK(s.error().code == rb::ErrorCode::InvalidArgument);
      CHECK(contains(s.error().message, part));
    };
    expect(pass.value()->record(VK_NULL_HANDLE, {.tlas = built.tlas, .camera = camera, .targets = {8, 8}}),
           "cmd is VK_NULL_HANDLE");
    expect(pass.value()->record(cmd, {.tlas = noRecords, .camera = camera, .targets = {8, 8}}), "no shading records");
    expect(pass.value()->record(cmd, {.tlas = rb::TlasInfo{}, .camera = camera, .targets = {8, 8}}),
           "TLAS is VK_NULL_HANDLE");
    expect(pass.value()->record(cmd, {.tlas = built.tlas, .camera = camera, .targets = {0, 8}}),
           "PrimaryShadingTargets::width and height");
    rb::PrimaryShadingSettings many;
    many.lightCandidates = 65;
    expect(pass.value()->record(cmd, {.tlas = built.tlas, .camera = camera, .targets = {8, 8}, .settings = many}),
           "lightCandidates 65 exceeds 64");
    rb::PrimaryRayCamera same = camera;
    for (int i = 0; i < 3; ++i) same.target[i] = same.eye[i];
    expect(pass.value()->record(cmd, {.tlas = built.tlas, .camera = same, .targets = {8, 8}}),
           "camera: camera eye equals target");
    auto lights = rb::LightList::create(fx.ctx());
    RB_REQUIRE_OK(lights);
    rb::PrimaryShadingSettings unrecorded;
    unrecorded.lights = lights.value().get();
    expect(pass.value()->record(cmd, {.tlas = built.tlas, .camera = camera, .targets = {8, 8}, .settings = unrecorded}),
           "PrimaryShadingSettings::lights: that LightList was not recorded this frame");
  });
  destroyScene(fx, built);
}
