// The reflection pass: a mirror shows what Embree says it reflects, in the right colour; surfaces above the
// roughness threshold trace nothing.
#include <catch2/catch_test_macros.hpp>

#include <glm/glm.hpp>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <string>

#include "synthetic_gbuffer.h"

using namespace rbtest;

namespace {

float halfToFloat(uint16_t h) {
  uint32_t sign = (h >> 15) & 1, exp = (h >> 10) & 31, mant = h & 1023;
  float v = exp == 0 ? std::ldexp(float(mant), -24) : std::ldexp(float(mant | 1024), int(exp) - 25);
  return sign ? -v : v;
}

struct ReflectionRun {
  std::vector<glm::vec4> radiance;
  rb::PassStats stats;
};

ReflectionRun runReflections(GpuFixture& fx, const TestScene& scene, const CpuGBuffer& cpu,
                             const std::vector<rb::Material>& materials, const rb::ReflectionSettings& settings) {
  auto pass = rb::ReflectionPass::create(fx.ctx());
  RB_REQUIRE_OK(pass);
  RB_REQUIRE_OK(pass.value()->setMaterials(materials, {}));
  ReflectionRun run;
  runPassFrame(
      fx, scene, cpu, true,
      [&](VkCommandBuffer cmd, const rb::GBufferDesc& desc, const rb::TlasInfo& tlas) {
        RB_REQUIRE_OK(pass.value()->record(cmd, {.gbuffer = desc, .tlas = tlas, .settings = settings}));
      },
      [&](const rb::GBufferDesc& desc) {
        std::vector<uint8_t> raw = readPassImage(fx, pass.value()->outputs().radiance, desc.width, desc.height, 8);
        run.radiance.resize(size_t(desc.width) * desc.height);
        for (size_t i = 0; i < run.radiance.size(); ++i) {
          uint16_t h[4];
          std::memcpy(h, raw.data() + 8 * i, 8);
          run.radiance[i] = glm::vec4(halfToFloat(h[0]), halfToFloat(h[1]), halfToFloat(h[2]), halfToFloat(h[3]));
        }
      });
  run.stats = pass.value()->stats();
  return run;
}

}  // namespace

TEST_CASE("a mirror reflects a coloured box where Embree says it should", "[reflection][embree]") {
  GpuFixture fx;
  TestScene scene;
  scene.meshes.push_back(rbsamples::makeGrid(12.0f, 12));
  const float mn[3] = {-0.6f, 0.0f, -0.6f}, mx[3] = {0.6f, 1.5f, 0.6f};
  scene.meshes.push_back(rbsamples::makeBox(mn, mx, 2));
  scene.instances.push_back({0, translation(0, 0, 0), 0});
  scene.instances.push_back({1, translation(0, 0, -1.5f), 1});
  std::vector<rb::Material> materials(2);
  materials[1].baseColor[0] = 0.8f;
  materials[1].baseColor[1] = 0.05f;
  materials[1].baseColor[2] = 0.05f;
  EmbreeScene embree;
  addToEmbree(embree, scene);
  SyntheticView view;
  view.eye = {0.3, 1.2, 4.0};
  view.target = {0.0, 0.2, -1.0};
  view.width = 96;
  view.height = 72;
  rb::ReflectionSettings settings;
  settings.lighting.sunDirection[0] = 0.3f;
  settings.lighting.sunDirection[1] = 1.0f;
  settings.lighting.sunDirection[2] = 0.6f;
  // Explicit lighting, so the reference below reads the same values the pass shades with.
  for (int i = 0; i < 3; ++i)
    settings.lighting.sunRadiance[i] = rb::kDefaultSunRadiance,
    settings.lighting.skyRadiance[i] = rb::kDefaultSkyRadiance[i];
  settings.lighting.ambientIntensity = rb::kDefaultAmbientIntensity;

  SECTION("mirror floor") {
    CpuGBuffer cpu = traceGBuffer(embree, view, {0.0f, 1.0f});  // floor a mirror, box rough
    ReflectionRun run = runReflections(fx, scene, cpu, materials, settings);
    uint32_t boxInMirror = 0, red = 0, skyInMirror = 0, sky = 0, boxPixels = 0, boxTraced = 0, floorPixels = 0;
    for (uint32_t y = 1; y + 1 < view.height; ++y) {
      for (uint32_t x = 1; x + 1 < view.width; ++x) {
        size_t i = size_t(y) * view.width + x;
        if (!cpu.hit[i]) continue;
        if (cpu.instance[i] == 1) {
          ++boxPixels;
          boxTraced += run.radiance[i].a != 0.0f;  // rough: no ray
          continue;
        }
        ++floorPixels;
        // Where does the mirror ray from this floor point go? Skip pixels whose neighbours disagree (edges).
        auto mirrorHit = [&](size_t j) {
          glm::dvec3 v = glm::normalize(cpu.position[j] - view.eye);
          glm::dvec3 r = glm::reflect(v, glm::dvec3(0, 1, 0));
          glm::dvec3 o = cpu.position[j] + glm::dvec3(0, 1e-4, 0);
          float of[3] = {float(o.x), float(o.y), float(o.z)}, d[3] = {float(r.x), float(r.y), float(r.z)};
          ReferenceHit h = embree.intersect(of, d, 0.0f, 1e30f);
          return h.hit ? int(h.instanceId) : -1;
        };
        int target = mirrorHit(i);
        bool edge = false;
        for (int dy = -1; dy <= 1; ++dy) {
          for (int dx = -1; dx <= 1; ++dx) {
            size_t j = size_t(int(y) + dy) * view.width + size_t(int(x) + dx);
            edge |= !cpu.hit[j] || cpu.instance[j] != 0 || mirrorHit(j) != target;
          }
        }
        if (edge) continue;
        glm::vec4 c = run.radiance[i];
        REQUIRE(c.a == 1.0f);  // a mirror pixel traced its ray
        if (target == 1) {
          ++boxInMirror;
          red += c.r > 3.0f * c.g && c.r > 3.0f * c.b && c.r > 0.05f;
        } else if (target < 0) {
          ++skyInMirror;
          sky += std::fabs(c.r - settings.lighting.skyRadiance[0]) < 2e-3f &&
                 std::fabs(c.g - settings.lighting.skyRadiance[1]) < 2e-3f &&
                 std::fabs(c.b - settings.lighting.skyRadiance[2]) < 2e-3f;
        }
      }
    }
    INFO("box in mirror " << boxInMirror << " (" << red << " red), sky " << skyInMirror << " (" << sky << ")");
    REQUIRE(boxInMirror > 100);
    REQUIRE(skyInMirror > 100);
    CHECK(red == boxInMirror);
    CHECK(sky == skyInMirror);
    CHECK(boxTraced == 0);
    // Rays are counted: one reflection ray per mirror pixel (every floor pixel, no box pixel), plus a shadow
    // ray where a reflection ray hits a box face that faces the sun.
    uint64_t tracedPixels = 0, allFloor = 0, shadowRays = 0;
    const glm::dvec3 toSun = glm::normalize(glm::dvec3(
        settings.lighting.sunDirection[0], settings.lighting.sunDirection[1], settings.lighting.sunDirection[2]));
    for (size_t i = 0; i < run.radiance.size(); ++i) {
      tracedPixels += run.radiance[i].a != 0.0f;
      if (!cpu.hit[i] || cpu.instance[i] != 0) continue;
      ++allFloor;
      glm::dvec3 v = glm::normalize(cpu.position[i] - view.eye);
      glm::dvec3 r = glm::reflect(v, glm::dvec3(0, 1, 0));
      glm::dvec3 o = cpu.position[i] + glm::dvec3(0, 1e-4, 0);
      float of[3] = {float(o.x), float(o.y), float(o.z)}, d[3] = {float(r.x), float(r.y), float(r.z)};
      ReferenceHit h = embree.intersect(of, d, 0.0f, 1e30f);
      if (!h.hit) continue;
      glm::dvec3 n = glm::normalize(glm::dvec3(h.geometricNormal[0], h.geometricNormal[1], h.geometricNormal[2]));
      if (glm::dot(n, r) > 0) n = -n;
      shadowRays += glm::dot(n, toSun) > 0.0;
    }
    CHECK(tracedPixels == allFloor);
    INFO("rays " << run.stats.rays << ", mirror pixels " << tracedPixels << ", expected shadow rays " << shadowRays);
    REQUIRE(shadowRays > 20);
    CHECK(double(run.stats.rays) >= double(tracedPixels + shadowRays) * 0.98);
    CHECK(double(run.stats.rays) <= double(tracedPixels + shadowRays) * 1.02);
    CHECK(floorPixels > 0);
    CHECK(boxPixels > 0);
  }

  SECTION("a surface rougher than the threshold traces no reflection rays") {
    CpuGBuffer cpu = traceGBuffer(embree, view, {0.8f, 1.0f});
    ReflectionRun run = runReflections(fx, scene, cpu, materials, settings);
    uint32_t traced = 0;
    for (const glm::vec4& c : run.radiance) traced += c.a != 0.0f;
    CHECK(traced == 0);
    CHECK(run.stats.rays == 0);
  }
}

TEST_CASE("reflection input errors name the problem", "[reflection][bad-input]") {
  GpuFixture fx;
  auto pass = rb::ReflectionPass::create(fx.ctx());
  RB_REQUIRE_OK(pass);
  rb::Material m;
  m.baseColorTexture = 3;
  auto s = pass.value()->setMaterials(std::span(&m, 1), {});
  REQUIRE(!s.ok());
  CHECK(s.error().message.find("texture 3") != std::string::npos);
  CHECK(!pass.value()->setMaterials({}, {}).ok());
}

TEST_CASE("reflection hits are lit by the many-light pass's light list", "[reflection][many_lights]") {
  GpuFixture fx;
  TestScene scene;
  scene.meshes.push_back(rbsamples::makeGrid(12.0f, 12));
  const float mn[3] = {-0.6f, 0.0f, -0.6f}, mx[3] = {0.6f, 1.5f, 0.6f};
  scene.meshes.push_back(rbsamples::makeBox(mn, mx, 2));
  scene.instances.push_back({0, translation(0, 0, 0), 0});
  scene.instances.push_back({1, translation(0, 0, -1.5f), 1});
  std::vector<rb::Material> materials(2);
  materials[1].baseColor[0] = 0.8f, materials[1].baseColor[1] = 0.3f, materials[1].baseColor[2] = 0.1f;
  EmbreeScene embree;
  addToEmbree(embree, scene);
  SyntheticView view;
  view.eye = {0.3, 1.2, 4.0};
  view.target = {0.0, 0.2, -1.0};
  view.width = 96;
  view.height = 72;
  CpuGBuffer cpu = traceGBuffer(embree, view, {0.0f, 1.0f});  // floor a mirror
  // No sun, a black sky, no ambient: the point light in front of the box is the only light.
  rb::ReflectionSettings settings;
  settings.lighting.explicitValues = true;
  settings.lighting.noSun = true;
  rb::LightSource light;
  light.light.type = rb::LightType::Point;
  light.light.position[0] = 0.4, light.light.position[1] = 1.0, light.light.position[2] = 0.2;
  light.intensity = 5.0f;
  light.color[1] = 0.8f;
  auto lights = rb::LightList::create(fx.ctx());
  RB_REQUIRE_OK(lights);
  auto pass = rb::ReflectionPass::create(fx.ctx());
  RB_REQUIRE_OK(pass);
  RB_REQUIRE_OK(pass.value()->setMaterials(materials, {}));
  std::vector<glm::vec4> lit, unlit;
  auto read = [&](const rb::GBufferDesc& desc, std::vector<glm::vec4>& out) {
    std::vector<float> rgba = readRgba16f(fx, pass.value()->outputs().radiance, desc.width, desc.height);
    out.resize(size_t(desc.width) * desc.height);
    std::memcpy(out.data(), rgba.data(), rgba.size() * sizeof(float));
  };
  for (bool withLights : {true, false}) {
    runPassFrame(
        fx, scene, cpu, true,
        [&](VkCommandBuffer cmd, const rb::GBufferDesc& desc, const rb::TlasInfo& tlas) {
          rb::ReflectionSettings s = settings;
          if (withLights) {
            RB_REQUIRE_OK(lights.value()->record(cmd, tlas, std::span(&light, 1)));
            s.lights = lights.value().get();
          }
          RB_REQUIRE_OK(pass.value()->record(cmd, {.gbuffer = desc, .tlas = tlas, .settings = s}));
        },
        [&](const rb::GBufferDesc& desc) { read(desc, withLights ? lit : unlit); });
  }
  // The reference: the box point the mirror ray hits, lit by the light: (albedo / pi + 0.04 / pi) * E.
  uint32_t compared = 0, agree = 0, dark = 0;
  const glm::dvec3 lp(light.light.position[0], light.light.position[1], light.light.position[2]);
  for (uint32_t y = 0; y < view.height; ++y) {
    for (uint32_t x = 0; x < view.width; ++x) {
      size_t i = size_t(y) * view.width + x;
      if (!cpu.hit[i] || cpu.instance[i] != 0) continue;
      glm::dvec3 v = glm::normalize(cpu.position[i] - view.eye);
      glm::dvec3 r = glm::reflect(v, glm::dvec3(0, 1, 0));
      glm::dvec3 o = cpu.position[i] + glm::dvec3(0, 1e-4, 0);
      float of[3] = {float(o.x), float(o.y), float(o.z)}, d[3] = {float(r.x), float(r.y), float(r.z)};
      ReferenceHit h = embree.intersect(of, d, 0.0f, 1e30f);
      if (!h.hit || h.instanceId != 1) continue;
      glm::dvec3 p = o + r * double(h.t);
      glm::dvec3 n = glm::normalize(glm::dvec3(h.geometricNormal[0], h.geometricNormal[1], h.geometricNormal[2]));
      if (glm::dot(n, r) > 0) n = -n;
      glm::dvec3 toLight = lp - p;
      double dist = glm::length(toLight);
      toLight /= dist;
      double cosine = glm::dot(n, toLight);
      // Skip box edges (a neighbour's mirror ray may hit another face) and faces turned from the light.
      if (cosine < 0.05 || std::fabs(std::fabs(n.x) + std::fabs(n.y) + std::fabs(n.z) - 1.0) > 1e-3) continue;
      glm::dvec3 e = glm::dvec3(light.color[0], light.color[1], light.color[2]) * double(light.intensity) * cosine /
                     (dist * dist);
      glm::dvec3 expected =
          (glm::dvec3(materials[1].baseColor[0], materials[1].baseColor[1], materials[1].baseColor[2]) + 0.04) / M_PI *
          e;
      ++compared;
      bool ok = true;
      for (int c = 0; c < 3; ++c) ok &= std::fabs(lit[i][c] - expected[c]) <= 0.03 * expected[c] + 1e-3;
      agree += ok;
      dark += unlit[i].r == 0.0f && unlit[i].g == 0.0f && unlit[i].b == 0.0f;
    }
  }
  INFO("box pixels seen in the mirror and lit: " << compared << ", agree " << agree << ", black without lights "
                                                 << dark);
  REQUIRE(compared > 100);
  CHECK(double(agree) >= 0.97 * compared);  // a few pixels on a face's border hit the neighbouring face
  CHECK(dark == compared);

  SECTION("a light list not recorded this frame is an error") {
    runPassFrame(
        fx, scene, cpu, true,
        [&](VkCommandBuffer cmd, const rb::GBufferDesc& desc, const rb::TlasInfo& tlas) {
          rb::ReflectionSettings s = settings;
          s.lights = lights.value().get();
          rb::Status st = pass.value()->record(cmd, {.gbuffer = desc, .tlas = tlas, .settings = s});
          REQUIRE_FALSE(st);
          CHECK(st.error().message.find("not recorded this frame") != std::string::npos);
        },
        [](const rb::GBufferDesc&) {});
  }
}

TEST_CASE("reflections with and without invocation reorder agree", "[reflection][invocation_reorder]") {
  TestScene scene;
  scene.meshes.push_back(rbsamples::makeGrid(12.0f, 12));
  const float mn[3] = {-0.6f, 0.0f, -0.6f}, mx[3] = {0.6f, 1.5f, 0.6f};
  scene.meshes.push_back(rbsamples::makeBox(mn, mx, 2));
  scene.instances.push_back({0, translation(0, 0, 0), 0});
  scene.instances.push_back({1, translation(0, 0, -1.5f), 1});
  scene.instances.push_back({1, translation(-2.0f, 0, -0.5f), 2});
  std::vector<rb::Material> materials(3);
  materials[1].baseColor[0] = 0.8f, materials[1].baseColor[1] = 0.05f, materials[1].baseColor[2] = 0.05f;
  materials[2].baseColor[0] = 0.05f, materials[2].baseColor[1] = 0.7f, materials[2].baseColor[2] = 0.2f;
  EmbreeScene embree;
  addToEmbree(embree, scene);
  SyntheticView view;
  view.eye = {0.3, 1.2, 4.0};
  view.target = {0.0, 0.2, -1.0};
  view.width = 96;
  view.height = 72;
  // A glossy floor (several GGX rays per pixel, divergent hits) and mirror boxes.
  CpuGBuffer cpu = traceGBuffer(embree, view, {0.2f, 0.0f, 0.0f});
  rb::ReflectionSettings settings;
  settings.raysPerPixel = 4;
  settings.lighting.sunDirection[0] = 0.3f, settings.lighting.sunDirection[1] = 1.0f,
  settings.lighting.sunDirection[2] = 0.6f;
  rb::ReflectionSettings plainSettings = settings;
  settings.invocationReorder = true;  // opt-in

  // Each run on a fresh context, so both trace at the same frame index (the GGX samples' seed).
  bool supported = false;
  std::string deviceName;
  auto run = [&](const rb::ReflectionSettings& s) {
    GpuFixture fx;
    supported = fx.ctx().deviceInfo().invocationReorder;
    deviceName = fx.device().deviceName();
    return runReflections(fx, scene, cpu, materials, s);
  };
  ReflectionRun reordered = run(settings);
  ReflectionRun plain = run(plainSettings);
  REQUIRE(reordered.radiance.size() == plain.radiance.size());
  // Same rays, same shading: only the order the hits are shaded in may differ, and with it nothing but float
  // rounding of the shading (none in practice; the tolerance is for a driver that fuses differently).
  float worst = 0.0f;
  uint32_t traced = 0;
  for (size_t i = 0; i < plain.radiance.size(); ++i) {
    const glm::vec4 d = glm::abs(reordered.radiance[i] - plain.radiance[i]);
    worst = std::max(worst, std::max(std::max(d.r, d.g), std::max(d.b, d.a)));
    traced += plain.radiance[i].a != 0.0f;
  }
  INFO("device " << deviceName << ", reorder " << supported << ", worst difference " << worst);
  REQUIRE(traced > 1000);
  CHECK(worst <= 1e-3f);
  CHECK(reordered.stats.rays == plain.stats.rays);
  if (!supported) SKIP("the device has no VK_NV_ray_tracing_invocation_reorder: both runs took the plain pipeline");
}

TEST_CASE("the reflection pass says whether it reordered", "[reflection][invocation_reorder]") {
  GpuFixture fx;
  TestScene scene;
  scene.meshes.push_back(rbsamples::makeGrid(4.0f, 4));
  scene.instances.push_back({0, translation(0, 0, 0), 0});
  EmbreeScene embree;
  addToEmbree(embree, scene);
  SyntheticView view;
  view.eye = {0.0, 1.0, 2.0};
  view.target = {0.0, 0.0, 0.0};
  view.width = 16;
  view.height = 16;
  CpuGBuffer cpu = traceGBuffer(embree, view, {0.0f});
  std::vector<rb::Material> materials(1);
  const bool supported = fx.ctx().deviceInfo().invocationReorder;
  for (bool requested : {true, false}) {
    auto pass = rb::ReflectionPass::create(fx.ctx());
    RB_REQUIRE_OK(pass);
    RB_REQUIRE_OK(pass.value()->setMaterials(materials, {}));
    rb::ReflectionSettings settings;
    settings.invocationReorder = requested;
    runPassFrame(
        fx, scene, cpu, true,
        [&](VkCommandBuffer cmd, const rb::GBufferDesc& desc, const rb::TlasInfo& tlas) {
          RB_REQUIRE_OK(pass.value()->record(cmd, {.gbuffer = desc, .tlas = tlas, .settings = settings}));
        },
        [](const rb::GBufferDesc&) {});
    // Requested on a device without it: the plain pipeline, no error (lavapipe); not requested: never.
    CHECK(pass.value()->reordered() == (supported && requested));
  }
}
