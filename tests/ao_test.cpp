// The AO pass against ground truth: Embree's AO over a procedural scene, and analytic open fractions.
#include <catch2/catch_test_macros.hpp>

#include <glm/glm.hpp>

#include <cmath>
#include <random>

#include "synthetic_gbuffer.h"

using namespace rbtest;

namespace {

std::vector<float> runAo(GpuFixture& fx, const TestScene& scene, const CpuGBuffer& cpu, const rb::AoSettings& settings,
                         rb::PassStats* stats = nullptr) {
  auto pass = rb::AoPass::create(fx.ctx());
  RB_REQUIRE_OK(pass);
  std::vector<float> ao;
  runPassFrame(
      fx, scene, cpu, false,
      [&](VkCommandBuffer cmd, const rb::GBufferDesc& desc, const rb::TlasInfo& tlas) {
        RB_REQUIRE_OK(pass.value()->record(cmd, {.gbuffer = desc, .tlas = tlas, .settings = settings}));
      },
      [&](const rb::GBufferDesc& desc) { ao = readR16f(fx, pass.value()->outputs().ao, desc.width, desc.height); });
  if (stats) *stats = pass.value()->stats();
  return ao;
}

// Embree AO: `rays` independent cosine-weighted directions around the geometric normal, binary within range.
std::vector<double> referenceAo(const EmbreeScene& embree, const CpuGBuffer& g, uint32_t rays, float range) {
  std::vector<double> ao(g.hit.size(), 1.0);
  std::mt19937 rng(1234);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (size_t i = 0; i < g.hit.size(); ++i) {
    if (!g.hit[i]) continue;
    glm::dvec3 n(g.normal[i]);
    glm::dvec3 t = glm::normalize(std::fabs(n.x) > 0.5 ? glm::cross(n, glm::dvec3(0, 1, 0))
                                                       : glm::cross(n, glm::dvec3(1, 0, 0)));
    glm::dvec3 b = glm::cross(n, t);
    glm::dvec3 o = g.position[i] + n * 1e-4;
    float of[3] = {float(o.x), float(o.y), float(o.z)};
    uint32_t open = 0;
    for (uint32_t k = 0; k < rays; ++k) {
      double r = std::sqrt(u(rng)), phi = 2.0 * M_PI * u(rng);
      glm::dvec3 d = r * std::cos(phi) * t + r * std::sin(phi) * b + std::sqrt(std::max(0.0, 1.0 - r * r)) * n;
      float df[3] = {float(d.x), float(d.y), float(d.z)};
      open += embree.intersect(of, df, 0.0f, range).hit ? 0 : 1;
    }
    ao[i] = double(open) / rays;
  }
  return ao;
}

}  // namespace

// The conformance scene seen from the side, at 64x48.
SyntheticView aoView() {
  SyntheticView view;
  view.eye = {-6.0, 3.5, 7.0};
  view.target = {0.0, 0.8, 0.0};
  view.fovYDegrees = 45.0;
  view.width = 64;
  view.height = 48;
  return view;
}

TEST_CASE("AO at 256 rays matches Embree's AO at 1024 rays", "[ao][embree]") {
  GpuFixture fx;
  TestScene scene = makeConformanceScene();
  EmbreeScene embree;
  addToEmbree(embree, scene);
  CpuGBuffer cpu = traceGBuffer(embree, aoView());
  rb::AoSettings settings;
  settings.raysPerPixel = 256;
  settings.range = 2.0f;
  rb::PassStats stats;
  std::vector<float> ao = runAo(fx, scene, cpu, settings, &stats);
  std::vector<double> ref = referenceAo(embree, cpu, 1024, settings.range);
  double sum = 0.0;
  uint32_t n = 0, hits = 0;
  double occludedSum = 0.0;
  for (size_t i = 0; i < cpu.hit.size(); ++i) {
    if (!cpu.hit[i]) {
      CHECK(ao[i] == 1.0f);  // sky pixels: open, no rays
      continue;
    }
    ++hits;
    double e = double(ao[i]) - ref[i];
    sum += e * e;
    occludedSum += 1.0 - ref[i];
    ++n;
  }
  double rmse = std::sqrt(sum / n);
  INFO("RMSE " << rmse << " over " << n << " pixels, mean occlusion " << occludedSum / n);
  REQUIRE(n > 1000);
  REQUIRE(occludedSum / n > 0.02);  // the scene has real occlusion to get right
  CHECK(rmse <= 0.03);
  CHECK(stats.rays == uint64_t(hits) * 256);  // counted: exactly the rays of the surface pixels
}

TEST_CASE("AO with unlimited range matches analytic open fractions", "[ao][analytic]") {
  GpuFixture fx;
  const uint32_t rays = 256;
  rb::AoSettings settings;
  settings.raysPerPixel = rays;
  settings.range = 1e6f;
  // Walls far larger than the view: within a few metres they are infinite planes. The floor the rays leave is
  // a grid of 1 m cells: a triangle whose vertices are kilometres away is intersected with an absolute error
  // of millimetres on NVIDIA (its vertices are float), more than any origin offset allows for.
  const float big = 2e4f;
  const float wallXMin[3] = {-1.0f, -1.0f, -big}, wallXMax[3] = {0.0f, big, big};  // the plane x = 0
  const float wallZMin[3] = {-big, -1.0f, -1.0f}, wallZMax[3] = {big, big, 0.0f};  // the plane z = 0
  auto check = [&](const TestScene& scene, double expected, glm::dvec3 eye, glm::dvec3 target) {
    EmbreeScene embree;
    addToEmbree(embree, scene);
    SyntheticView view;
    view.eye = eye;
    view.target = target;
    view.fovYDegrees = 40.0;
    view.width = 48;
    view.height = 36;
    CpuGBuffer cpu = traceGBuffer(embree, view);
    std::vector<float> ao = runAo(fx, scene, cpu, settings);
    double sigma = std::sqrt(expected * (1.0 - expected) / rays);
    uint32_t floorPixels = 0, within = 0;
    double mean = 0.0;
    for (size_t i = 0; i < cpu.hit.size(); ++i) {
      if (!cpu.hit[i] || cpu.instance[i] != 0) continue;
      if (cpu.position[i].x < 0.02 || cpu.position[i].z < 0.02) continue;  // the open side of the walls only
      ++floorPixels;
      mean += ao[i];
      // 3 standard errors, plus the half-precision step of the stored value.
      within += std::fabs(ao[i] - expected) <= 3.0 * sigma + 1e-3;
    }
    mean /= floorPixels;
    INFO("expected " << expected << ", mean " << mean << " over " << floorPixels << " floor pixels, " << within
                     << " within 3 sigma");
    REQUIRE(floorPixels > 300);
    CHECK(double(within) / floorPixels >= 0.99);
    CHECK(std::fabs(mean - expected) <= 3.0 * sigma / std::sqrt(double(floorPixels)) + 2e-3);
  };
  TestScene open, wall, corner;
  for (TestScene* s : {&open, &wall, &corner}) {
    s->meshes.push_back(rbsamples::makeGrid(40.0f, 40));
    s->instances.push_back({0, translation(0, 0, 0)});
  }
  wall.meshes.push_back(rbsamples::makeBox(wallXMin, wallXMax));
  wall.instances.push_back({1, translation(0, 0, 0)});
  corner.meshes.push_back(rbsamples::makeBox(wallXMin, wallXMax));
  corner.meshes.push_back(rbsamples::makeBox(wallZMin, wallZMax));
  corner.instances.push_back({1, translation(0, 0, 0)});
  corner.instances.push_back({2, translation(0, 0, 0)});

  SECTION("open plane: 1") { check(open, 1.0, {3.0, 2.5, 3.0}, {1.5, 0.0, 1.5}); }
  SECTION("floor at the base of a tall wall: 1/2") { check(wall, 0.5, {3.0, 2.5, 3.0}, {1.0, 0.0, 1.5}); }
  SECTION("inside a cube corner: 1/4") { check(corner, 0.25, {3.0, 2.5, 3.0}, {1.0, 0.0, 1.0}); }
}

TEST_CASE("distance-weighted AO never occludes more than binary AO with the same rays", "[ao]") {
  TestScene scene = makeConformanceScene();
  EmbreeScene embree;
  addToEmbree(embree, scene);
  CpuGBuffer cpu = traceGBuffer(embree, aoView());
  rb::AoSettings settings;
  settings.raysPerPixel = 16;
  settings.range = 1.5f;
  // Fresh contexts go through the same frame numbers, so both runs trace the same directions (the noise is
  // seeded by pixel and frame).
  std::vector<float> binary, weighted;
  {
    GpuFixture fx;
    binary = runAo(fx, scene, cpu, settings);
  }
  {
    GpuFixture fx;
    settings.estimator = rb::AoEstimator::DistanceWeighted;
    weighted = runAo(fx, scene, cpu, settings);
  }
  uint32_t higher = 0, lower = 0;
  for (size_t i = 0; i < cpu.hit.size(); ++i) {
    if (!cpu.hit[i]) continue;
    higher += weighted[i] > binary[i] + 1e-3f;
    lower += weighted[i] < binary[i] - 1e-3f;  // half-float rounding only
  }
  CHECK(higher > 50);  // occluders at a distance count partly open
  CHECK(lower == 0);
}
