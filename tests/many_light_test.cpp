// ManyLightPass against ground truth: the room of many_light_scene.h lit by two point lights, a spot light and
// a directional light, traced per pixel and per light with Embree (exact mode); the stochastic
// mode's mean and convergence against the exact mode; culling by range and cone counted in rays; bad lights.
#include <catch2/catch_test_macros.hpp>

#include <glm/glm.hpp>

#include <bit>
#include <cmath>

#include "many_light_scene.h"

using namespace rbtest;

namespace {

// The irradiance formula of many_light_pass.h, in double: unshadowed, with `toLight`/`distance` to trace.
glm::dvec3 unshadowed(const rb::LightSource& s, glm::dvec3 p, glm::dvec3 n, glm::dvec3& toLight, double& distance) {
  const rb::Light& l = s.light;
  glm::dvec3 color(s.color[0], s.color[1], s.color[2]);
  double falloff = 1.0;
  if (l.type == rb::LightType::Directional) {
    toLight = glm::normalize(glm::dvec3(l.direction[0], l.direction[1], l.direction[2]));
    distance = 1e30;
  } else {
    glm::dvec3 d = glm::dvec3(l.position[0], l.position[1], l.position[2]) - p;
    distance = glm::length(d);
    toLight = d / distance;
    falloff = 1.0 / (distance * distance);
    if (l.range > 0.0f) falloff *= std::clamp(1.0 - std::pow(distance / l.range, 4.0), 0.0, 1.0);
    if (l.type == rb::LightType::Spot) {
      double outer = (l.spotOuterAngleDegrees == 0.0f ? 45.0 : l.spotOuterAngleDegrees) * M_PI / 180.0;
      double inner = s.spotInnerAngleDegrees * M_PI / 180.0;
      glm::dvec3 axis = glm::normalize(glm::dvec3(l.direction[0], l.direction[1], l.direction[2]));
      double scale = 1.0 / std::max(1e-3, std::cos(inner) - std::cos(outer));
      double c = std::clamp((glm::dot(-toLight, axis) - std::cos(outer)) * scale, 0.0, 1.0);
      falloff *= c * c;
    }
  }
  double cosine = glm::dot(n, toLight);
  if (cosine <= 0.0) return glm::dvec3(0.0);
  return color * double(s.intensity) * cosine * falloff;
}

struct Reference {
  std::vector<glm::dvec3> irradiance;
  std::vector<uint32_t> litMask;  // per pixel, bit i: light i lights the point (before shadows)
  std::vector<uint32_t> visible;  // per pixel, bit i: light i's shadow ray is free
};

Reference reference(const EmbreeScene& embree, const CpuGBuffer& g, const std::vector<rb::LightSource>& lights) {
  Reference r;
  r.irradiance.assign(g.hit.size(), glm::dvec3(0.0));
  r.litMask.assign(g.hit.size(), 0);
  r.visible.assign(g.hit.size(), 0);
  for (size_t i = 0; i < g.hit.size(); ++i) {
    if (!g.hit[i]) continue;
    glm::dvec3 n(g.normal[i]);
    glm::dvec3 o = g.position[i] + n * 1e-4;
    for (size_t k = 0; k < lights.size(); ++k) {
      glm::dvec3 toLight;
      double distance;
      glm::dvec3 e = unshadowed(lights[k], g.position[i], n, toLight, distance);
      if (e == glm::dvec3(0.0)) continue;
      r.litMask[i] |= 1u << k;
      float of[3] = {float(o.x), float(o.y), float(o.z)}, d[3] = {float(toLight.x), float(toLight.y), float(toLight.z)};
      float tMax = distance > 1e29 ? 1e30f : float(0.999 * distance);
      if (embree.intersect(of, d, 0.0f, tMax).hit) continue;
      r.visible[i] |= 1u << k;
      r.irradiance[i] += e;
    }
  }
  return r;
}

struct ManyLightRun {
  std::vector<float> rgba;
  rb::PassStats stats;
};

ManyLightRun runManyLights(GpuFixture& fx, const TestScene& scene, const CpuGBuffer& cpu,
                           const std::vector<rb::LightSource>& lights, const rb::ManyLightSettings& settings) {
  auto pass = rb::ManyLightPass::create(fx.ctx());
  RB_REQUIRE_OK(pass);
  ManyLightRun out;
  runPassFrame(
      fx, scene, cpu, false,
      [&](VkCommandBuffer cmd, const rb::GBufferDesc& desc, const rb::TlasInfo& tlas) {
        RB_REQUIRE_OK(
            pass.value()->record(cmd, {.gbuffer = desc, .tlas = tlas, .lights = lights, .settings = settings}));
      },
      [&](const rb::GBufferDesc& desc) {
        out.rgba = readRgba16f(fx, pass.value()->outputs().irradiance, desc.width, desc.height);
      });
  out.stats = pass.value()->stats();
  return out;
}

// Pixels whose 3x3 neighbourhood has the same shadow and light masks (edges are where the depth buffer's
// reconstruction and the reference's exact point may fall on different sides).
bool awayFromEdges(const Reference& r, const CpuGBuffer& g, int x, int y) {
  const int w = int(g.view.width), h = int(g.view.height);
  size_t i = size_t(y) * w + x;
  for (int dy = -1; dy <= 1; ++dy) {
    for (int dx = -1; dx <= 1; ++dx) {
      int nx = std::clamp(x + dx, 0, w - 1), ny = std::clamp(y + dy, 0, h - 1);
      size_t j = size_t(ny) * w + nx;
      if (g.hit[j] != g.hit[i] || r.visible[j] != r.visible[i] || r.litMask[j] != r.litMask[i]) return false;
    }
  }
  return true;
}

}  // namespace

TEST_CASE("many-light exact mode matches Embree's per-light shadow rays in a lit room", "[many_lights][embree]") {
  GpuFixture fx;
  TestScene scene = makeRoom();
  EmbreeScene embree;
  addToEmbree(embree, scene);
  CpuGBuffer cpu = traceGBuffer(embree, roomView());
  std::vector<rb::LightSource> lights = roomLights();
  Reference ref = reference(embree, cpu, lights);
  rb::ManyLightSettings exact;
  exact.mode = rb::ManyLightMode::Exact;
  ManyLightRun gpu = runManyLights(fx, scene, cpu, lights, exact);

  std::vector<float> refRgba(gpu.rgba.size(), 0.0f);
  std::vector<uint8_t> mask(cpu.hit.size(), 0);
  uint32_t compared = 0, shadowed = 0;
  for (int y = 0; y < int(cpu.view.height); ++y) {
    for (int x = 0; x < int(cpu.view.width); ++x) {
      size_t i = size_t(y) * cpu.view.width + x;
      for (int c = 0; c < 3; ++c) refRgba[4 * i + c] = float(ref.irradiance[i][c]);
      if (!cpu.hit[i] || !awayFromEdges(ref, cpu, x, y)) continue;
      mask[i] = 1;
      ++compared;
      shadowed += ref.visible[i] != ref.litMask[i];
    }
  }
  double error = relativeRmse(gpu.rgba, refRgba, mask);
  INFO("compared " << compared << " pixels (" << shadowed << " in some light's shadow): relative RMSE " << error);
  REQUIRE(compared > cpu.hit.size() / 2);
  CHECK(shadowed > compared / 10);  // the shadows matter
  CHECK(error <= 0.02);
  for (float v : gpu.rgba) REQUIRE(std::isfinite(v));
  // One ray per light that lights a pixel, no more.
  uint64_t expectedRays = 0;
  for (uint32_t m : ref.litMask) expectedRays += std::popcount(m);
  INFO("rays " << gpu.stats.rays << ", lights lighting pixels " << expectedRays);
  CHECK(double(gpu.stats.rays) <= 1.01 * double(expectedRays));
  CHECK(double(gpu.stats.rays) >= 0.99 * double(expectedRays));
}

TEST_CASE("many-light stochastic mode is unbiased and converges to the exact mode", "[many_lights]") {
  GpuFixture fx;
  TestScene scene = makeRoom();
  EmbreeScene embree;
  addToEmbree(embree, scene);
  CpuGBuffer cpu = traceGBuffer(embree, roomView(128, 96));
  std::vector<rb::LightSource> lights = manyRoomLights();
  rb::ManyLightSettings exact;
  exact.mode = rb::ManyLightMode::Exact;
  ManyLightRun reference = runManyLights(fx, scene, cpu, lights, exact);
  rb::ManyLightSettings one;
  one.raysPerPixel = 1;
  ManyLightRun noisy = runManyLights(fx, scene, cpu, lights, one);
  rb::ManyLightSettings eight;
  eight.raysPerPixel = 8;
  ManyLightRun better = runManyLights(fx, scene, cpu, lights, eight);

  std::vector<uint8_t> surface(cpu.hit.begin(), cpu.hit.end());
  auto mean = [&](const std::vector<float>& rgba) {
    double sum = 0.0;
    for (size_t i = 0; i < surface.size(); ++i)
      if (surface[i]) sum += rgba[4 * i] + rgba[4 * i + 1] + rgba[4 * i + 2];
    return sum;
  };
  double exactMean = mean(reference.rgba), noisyMean = mean(noisy.rgba);
  double rmse1 = relativeRmse(noisy.rgba, reference.rgba, surface);
  double rmse8 = relativeRmse(better.rgba, reference.rgba, surface);
  INFO("mean: exact " << exactMean << ", 1 ray " << noisyMean << "; relative RMSE 1 ray " << rmse1 << ", 8 rays "
                      << rmse8 << "; rays exact " << reference.stats.rays << ", 1 ray " << noisy.stats.rays);
  CHECK(std::fabs(noisyMean - exactMean) <= 0.03 * exactMean);
  CHECK(rmse1 > 0.02);  // it is noisy: the test would not see a wrong estimator otherwise
  CHECK(rmse8 <= 0.6 * rmse1);
  // A fixed budget: at most one ray per pixel, far fewer than one per light.
  uint32_t pixels = 0;
  for (uint8_t h : surface) pixels += h;
  CHECK(noisy.stats.rays <= pixels);
  CHECK(reference.stats.rays > 4 * uint64_t(pixels));
}

TEST_CASE("many-light rays are traced only where a light's range and cone reach", "[many_lights][culling]") {
  GpuFixture fx;
  TestScene scene = makeRoom();
  EmbreeScene embree;
  addToEmbree(embree, scene);
  CpuGBuffer cpu = traceGBuffer(embree, roomView());
  std::vector<rb::LightSource> lights;
  lights.push_back(pointLight({-3.0, 0.8, 0.5}, {1.0f, 1.0f, 1.0f}, 3.0f, 2.0f));
  rb::LightSource spot;
  spot.light.type = rb::LightType::Spot;
  spot.light.position[0] = 2.0, spot.light.position[1] = 4.0, spot.light.position[2] = 0.0;
  spot.light.direction[1] = -1.0f;
  spot.light.spotOuterAngleDegrees = 12.0f;
  spot.intensity = 30.0f;
  lights.push_back(spot);
  Reference ref = reference(embree, cpu, lights);
  uint64_t reached = 0, surface = 0;
  for (size_t i = 0; i < cpu.hit.size(); ++i) reached += std::popcount(ref.litMask[i]), surface += cpu.hit[i];
  for (rb::ManyLightMode mode : {rb::ManyLightMode::Exact, rb::ManyLightMode::Stochastic}) {
    rb::ManyLightSettings settings;
    settings.mode = mode;
    settings.raysPerPixel = 1;
    ManyLightRun gpu = runManyLights(fx, scene, cpu, lights, settings);
    INFO("mode " << int(mode) << ": rays " << gpu.stats.rays << ", light-pixel pairs in reach " << reached
                 << ", surface pixels " << surface);
    CHECK(reached < surface / 4);  // most of the room is out of both lights' reach
    CHECK(double(gpu.stats.rays) <= 1.01 * double(reached));
    CHECK(gpu.stats.rays > 0);
    // And the irradiance is 0 wherever no light reaches.
    uint32_t litOutside = 0;
    for (size_t i = 0; i < cpu.hit.size(); ++i)
      if (cpu.hit[i] && ref.litMask[i] == 0 && gpu.rgba[4 * i] + gpu.rgba[4 * i + 1] + gpu.rgba[4 * i + 2] > 0.0f)
        ++litOutside;
    CHECK(litOutside <= surface / 200);  // only edge pixels (reconstruction error)
  }
}

TEST_CASE("many-light bad lights fail naming the light and field; nothing is recorded", "[many_lights][bad_input]") {
  GpuFixture fx;
  TestScene scene = makeRoom();
  EmbreeScene embree;
  addToEmbree(embree, scene);
  CpuGBuffer cpu = traceGBuffer(embree, roomView(32, 24));
  auto pass = rb::ManyLightPass::create(fx.ctx());
  RB_REQUIRE_OK(pass);
  auto expectError = [&](std::vector<rb::LightSource> lights, const char* fragment) {
    runPassFrame(
        fx, scene, cpu, false,
        [&](VkCommandBuffer cmd, const rb::GBufferDesc& desc, const rb::TlasInfo& tlas) {
          rb::Status s = pass.value()->record(cmd, {.gbuffer = desc, .tlas = tlas, .lights = lights});
          REQUIRE_FALSE(s);
          INFO(s.error().message);
          CHECK(s.error().code == rb::ErrorCode::InvalidArgument);
          CHECK(s.error().message.find(fragment) != std::string::npos);
        },
        [](const rb::GBufferDesc&) {});
  };
  std::vector<rb::LightSource> lights = roomLights();
  lights[1].intensity = -1.0f;
  expectError(lights, "lights[1]: intensity");
  lights = roomLights();
  lights[0].intensity = NAN;
  expectError(lights, "lights[0]: intensity");
  lights = roomLights();
  lights[2].spotInnerAngleDegrees = 50.0f;  // outer 35
  expectError(lights, "lights[2]: spotInnerAngleDegrees");
  lights = roomLights();
  lights[0].light.position[1] = INFINITY;
  expectError(lights, "lights[0]: Light::position must be finite");
  expectError(std::vector<rb::LightSource>(70000, roomLights()[0]), "70000 lights exceed kMaxLights");
  // No lights: black, no rays.
  ManyLightRun none = runManyLights(fx, scene, cpu, {}, {});
  uint32_t wrong = 0;
  for (size_t i = 0; i < none.rgba.size(); ++i) wrong += none.rgba[i] != (i % 4 == 3 ? 1.0f : 0.0f);
  CHECK(wrong == 0);
  CHECK(none.stats.rays == 0);
}

TEST_CASE("the effects front end's local lights are the many-light pass's, and cost nothing when disabled",
          "[many_lights][hybrid_effects]") {
  GpuFixture fx;
  TestScene scene = makeRoom();
  EmbreeScene embree;
  addToEmbree(embree, scene);
  CpuGBuffer cpu = traceGBuffer(embree, roomView(64, 48));
  std::vector<rb::LightSource> lights = roomLights();
  rb::ManyLightSettings exact;
  exact.mode = rb::ManyLightMode::Exact;
  ManyLightRun direct = runManyLights(fx, scene, cpu, lights, exact);

  rb::HybridEffectsDesc desc;
  desc.effects = rb::kEffectLocalLights;
  desc.localLights.mode = rb::ManyLightMode::Exact;
  auto service = rb::AccelerationStructureService::create(fx.ctx());
  RB_REQUIRE_OK(service);
  BuiltScene built = buildScene(fx, *service.value(), scene);
  {
    auto fxDisabled = rb::HybridEffects::create(fx.ctx(), service.value().get(), {});
    RB_REQUIRE_OK(fxDisabled);
    CHECK(fxDisabled.value()->localLightPass() == nullptr);
    auto effects = rb::HybridEffects::create(fx.ctx(), service.value().get(), desc);
    RB_REQUIRE_OK(effects);
    REQUIRE(effects.value()->localLightPass() != nullptr);
    GpuGBuffer gbuffer(fx, cpu);
    fx.runFrame([&](VkCommandBuffer cmd) {
      rb::HybridFrame frame;
      frame.gbuffer = gbuffer.desc();
      frame.instances = built.instances;
      frame.localLights = lights;
      RB_REQUIRE_OK(effects.value()->record(cmd, frame));
    });
    const rb::HybridOutputs& out = effects.value()->outputs();
    REQUIRE(out.localLights.image != VK_NULL_HANDLE);
    CHECK(out.localLights.format == VK_FORMAT_R16G16B16A16_SFLOAT);
    CHECK(out.shadow.width == 1);  // only what is enabled: the other outputs are the 1x1 neutral images
    CHECK(effects.value()->shadowPass() == nullptr);
    std::vector<float> viaFrontEnd = readRgba16f(fx, out.localLights.image, cpu.view.width, cpu.view.height);
    CHECK(viaFrontEnd == direct.rgba);
    for (uint32_t i = 0; i < fx.ctx().framesInFlight(); ++i) fx.ctx().beginFrame();
    (void)fx.device().waitIdle();
    CHECK(effects.value()->stats().localLights.rays == direct.stats.rays);
  }
  destroyScene(fx, built);
}
