// Sun visibility from the screen (ReflectionFrame::sunVisibility): a glossy floor reflects a tall box whose front face
// is partly on screen, partly above the screen's top edge and partly hidden from the camera by a floating plank. A hit
// on the visible face reads the ShadowPass's visibility there and saves its shadow ray, agreeing with the traced
// image; a hit off screen or hidden behind the plank traces as before, whatever the image says; mirrors always trace.
#include <catch2/catch_test_macros.hpp>

#include <glm/glm.hpp>

#include <cmath>
#include <vector>

#include "effects_rig.h"
#include "synthetic_gbuffer.h"

using namespace rbtest;

namespace {

// Floor 0.05 is glossy but narrow (rays stay within a few milliradians of the mirror direction, so Embree's mirror
// ray says where they go); the cache reads for pixels at least 0.04 rough.
constexpr float kFloorRoughness = 0.05f;
constexpr float kCacheRoughness = 0.04f;
// Traced against cached where the hit is on screen: the mean difference over those pixels, relative to their mean,
// and the share of pixels differing by more than 5% (a hard shadow's edge seen from another point within a pixel).
constexpr double kMeanRelativeTolerance = 0.01;
constexpr double kEdgePixelShare = 0.03;

enum class HitKind { None, NoSun, Visible, Offscreen, Hidden };

struct Scene {
  TestScene scene;
  std::vector<rb::Material> materials;
  EmbreeScene embree;
  SyntheticView view;
  glm::dvec3 toSun = glm::normalize(glm::dvec3(0.3, 1.0, 0.6));
};

void makeScene(Scene& s) {
  s.scene.meshes.push_back(rbsamples::makeGrid(12.0f, 12));
  const float boxMin[3] = {-0.6f, 0.0f, -0.6f}, boxMax[3] = {0.6f, 4.0f, 0.6f};  // above the screen's top
  s.scene.meshes.push_back(rbsamples::makeBox(boxMin, boxMax, 4));
  const float plankMin[3] = {-0.5f, 0.9f, -0.05f}, plankMax[3] = {0.5f, 1.1f, 0.05f};  // hides some of the face
  s.scene.meshes.push_back(rbsamples::makeBox(plankMin, plankMax, 1));
  const float cubeMin[3] = {-0.2f, -0.2f, -0.2f}, cubeMax[3] = {0.2f, 0.2f, 0.2f};  // off screen, shades the face
  s.scene.meshes.push_back(rbsamples::makeBox(cubeMin, cubeMax, 1));
  s.scene.instances.push_back({0, translation(0, 0, 0), 0});
  s.scene.instances.push_back({1, translation(0, 0, -1.5f), 1});
  s.scene.instances.push_back({2, translation(0, 0, 0), 2});
  s.scene.instances.push_back({3, translation(0.2f, 3.0f, 0.3f), 2});
  s.materials.resize(3);
  s.materials[1].baseColor[0] = 0.8f, s.materials[1].baseColor[1] = 0.6f, s.materials[1].baseColor[2] = 0.3f;
  s.materials[2].baseColor[0] = 0.2f, s.materials[2].baseColor[1] = 0.3f, s.materials[2].baseColor[2] = 0.6f;
  addToEmbree(s.embree, s.scene);
  s.view.eye = {0.3, 2.0, 3.0};
  s.view.target = {0.0, 0.0, -1.0};
  s.view.width = 128;
  s.view.height = 96;
}

// Whether the G-buffer's surface at `q` is the one at `p` on instance `instance` (the pass's test, in double).
bool sameSurface(const CpuGBuffer& cpu, size_t q, const glm::dvec3& p, uint32_t instance) {
  if (!cpu.hit[q] || cpu.instance[q] != instance) return false;
  const glm::dvec3 n = glm::normalize(glm::dvec3(cpu.normal[q]));
  return std::fabs(glm::dot(p - cpu.position[q], n)) < 0.005 * glm::length(p - cpu.view.eye);
}

// Where the mirror ray of floor pixel `i` lands, as the pass should treat it; None where the hit lands near the
// screen's edge or the 3x3 pixels it projects to disagree (an edge a glossy ray may cross either way). `lit`: whether
// the hit sees the sun (Embree).
HitKind classify(const Scene& s, const CpuGBuffer& cpu, size_t i, bool& lit) {
  const glm::dvec3 v = glm::normalize(cpu.position[i] - s.view.eye);
  const glm::dvec3 r = glm::reflect(v, glm::dvec3(0, 1, 0));
  const glm::dvec3 o = cpu.position[i] + glm::dvec3(0, 1e-4, 0);
  const float of[3] = {float(o.x), float(o.y), float(o.z)}, d[3] = {float(r.x), float(r.y), float(r.z)};
  const ReferenceHit h = s.embree.intersect(of, d, 0.0f, 1e30f);
  if (!h.hit) return HitKind::None;
  glm::dvec3 n = glm::normalize(glm::dvec3(h.geometricNormal[0], h.geometricNormal[1], h.geometricNormal[2]));
  if (glm::dot(n, r) > 0) n = -n;
  if (glm::dot(n, s.toSun) <= 0.0) return HitKind::NoSun;
  const glm::dvec3 p = o + r * double(h.t);
  const glm::dvec3 q = p + n * 1e-3;
  const float qf[3] = {float(q.x), float(q.y), float(q.z)};
  const float sf[3] = {float(s.toSun.x), float(s.toSun.y), float(s.toSun.z)};
  lit = !s.embree.intersect(qf, sf, 0.0f, 1e30f).hit;
  const glm::dvec4 clip = glm::dmat4(cpu.projection) * glm::dmat4(cpu.viewMatrix) * glm::dvec4(p - s.view.eye, 1.0);
  if (clip.w <= 0.0) return HitKind::Offscreen;
  const glm::dvec2 px = (glm::dvec2(clip) / clip.w * 0.5 + 0.5) * glm::dvec2(s.view.width, s.view.height);
  const double w = s.view.width, hgt = s.view.height, margin = 2.0;  // pixels: a glossy ray lands beside the mirror's
  if (px.x < -margin || px.y < -margin || px.x >= w + margin || px.y >= hgt + margin) return HitKind::Offscreen;
  if (px.x < margin || px.y < margin || px.x >= w - margin || px.y >= hgt - margin) return HitKind::None;
  int same = 0;
  for (int dy = -1; dy <= 1; ++dy) {
    for (int dx = -1; dx <= 1; ++dx) {
      const size_t k = size_t(int(px.y) + dy) * s.view.width + size_t(int(px.x) + dx);
      same += sameSurface(cpu, k, p, h.instanceId);
    }
  }
  return same == 9 ? HitKind::Visible : same == 0 ? HitKind::Hidden : HitKind::None;
}

struct Runs {
  std::vector<float> traced, cached, zero;  // RGBA per pixel: no image, the ShadowPass's, an all-shadow image
  rb::PassStats tracedStats, cachedStats, zeroStats;
};

// One frame: hard sun shadows on the G-buffer, then three reflection passes over the same rays (same frame index).
Runs runFrame(GpuFixture& fx, const Scene& s, const CpuGBuffer& cpu) {
  auto shadow = rb::ShadowPass::create(fx.ctx());
  RB_REQUIRE_OK(shadow);
  std::unique_ptr<rb::ReflectionPass> passes[3];
  for (auto& p : passes) {
    auto made = rb::ReflectionPass::create(fx.ctx());
    RB_REQUIRE_OK(made);
    p = std::move(made.value());
    RB_REQUIRE_OK(p->setMaterials(s.materials, {}));
  }
  const std::vector<uint16_t> zeros(size_t(s.view.width) * s.view.height, 0);
  SampledImage allShadow = uploadSampledImage(fx, VK_FORMAT_R16_SFLOAT, VK_IMAGE_ASPECT_COLOR_BIT, s.view.width,
                                              s.view.height, zeros.data(), zeros.size() * 2);
  rb::ReflectionSettings settings;
  for (int i = 0; i < 3; ++i) settings.lighting.sunDirection[i] = float(s.toSun[i]);
  settings.raysPerPixel = 1;
  settings.sunVisibilityMinRoughness = kCacheRoughness;
  Runs out;
  runPassFrame(
      fx, s.scene, cpu, true,
      [&](VkCommandBuffer cmd, const rb::GBufferDesc& g, const rb::TlasInfo& tlas) {
        rb::Light sun;
        for (int i = 0; i < 3; ++i) sun.direction[i] = float(s.toSun[i]);
        RB_REQUIRE_OK(shadow.value()->record(cmd, {.gbuffer = g, .tlas = tlas, .light = sun}));
        const rb::ShadowOutputs& so = shadow.value()->outputs();
        const rb::GBufferImage images[3] = {{},
                                            {.view = so.visibilityView, .width = so.width, .height = so.height},
                                            {.view = allShadow.view}};
        for (int k = 0; k < 3; ++k) {
          RB_REQUIRE_OK(
              passes[k]->record(cmd, {.gbuffer = g, .tlas = tlas, .settings = settings, .sunVisibility = images[k]}));
        }
      },
      [&](const rb::GBufferDesc& g) {
        out.traced = readRgba16f(fx, passes[0]->outputs().radiance, g.width, g.height);
        out.cached = readRgba16f(fx, passes[1]->outputs().radiance, g.width, g.height);
        out.zero = readRgba16f(fx, passes[2]->outputs().radiance, g.width, g.height);
      });
  out.tracedStats = passes[0]->stats();
  out.cachedStats = passes[1]->stats();
  out.zeroStats = passes[2]->stats();
  destroySampledImage(fx, allShadow);
  return out;
}

float luminance(const std::vector<float>& rgba, size_t i) {
  return 0.2126f * rgba[4 * i] + 0.7152f * rgba[4 * i + 1] + 0.0722f * rgba[4 * i + 2];
}

bool identical(const std::vector<float>& a, const std::vector<float>& b, size_t i) {
  for (int c = 0; c < 4; ++c)
    if (std::fabs(a[4 * i + c] - b[4 * i + c]) > 1e-4f * std::max(1.0f, std::fabs(a[4 * i + c]))) return false;
  return true;
}

}  // namespace

TEST_CASE("reflection hits read the sun from the shadow image only where the hit is the surface on screen",
          "[reflection][sun-cache]") {
  GpuFixture fx;
  Scene s;
  makeScene(s);
  const CpuGBuffer cpu = traceGBuffer(s.embree, s.view, {kFloorRoughness, 1.0f, 1.0f, 1.0f});
  const Runs run = runFrame(fx, s, cpu);

  uint32_t visible = 0, visibleLit = 0, offscreen = 0, hidden = 0, visibleDarker = 0, offDiffer = 0, hiddenDiffer = 0;
  uint32_t edgePixels = 0, floorPixels = 0;
  double sumTraced = 0.0, sumDiff = 0.0;
  for (size_t i = 0; i < cpu.hit.size(); ++i) {
    if (!cpu.hit[i] || cpu.instance[i] != 0) continue;
    ++floorPixels;
    bool lit = false;
    const HitKind kind = classify(s, cpu, i, lit);
    if (kind == HitKind::Visible) {
      ++visible;
      const double t = luminance(run.traced, i), c = luminance(run.cached, i);
      sumTraced += t, sumDiff += std::fabs(c - t);
      edgePixels += std::fabs(c - t) > 0.05 * t;
      // The all-shadow image darkens every lit hit that read it (a shadowed one has no sun light to lose).
      visibleLit += lit;
      visibleDarker += lit && luminance(run.zero, i) < 0.95f * luminance(run.traced, i);
    } else if (kind == HitKind::Offscreen || kind == HitKind::Hidden) {
      // The cache must not be read: the traced result, bit for bit the same rays, whatever the image says.
      const bool differs = !identical(run.traced, run.zero, i) || !identical(run.traced, run.cached, i);
      (kind == HitKind::Offscreen ? ++offscreen : ++hidden);
      (kind == HitKind::Offscreen ? offDiffer : hiddenDiffer) += differs;
    }
  }
  const uint64_t saved = run.tracedStats.rays - run.cachedStats.rays;
  INFO("floor " << floorPixels << ", hits visible " << visible << " (" << visibleLit << " lit, " << visibleDarker
                << " of them darker with an all-shadow image"
                << "), off screen " << offscreen << " (" << offDiffer << " differ), hidden " << hidden << " ("
                << hiddenDiffer << " differ); rays traced " << run.tracedStats.rays << ", cached "
                << run.cachedStats.rays << ", all-shadow image " << run.zeroStats.rays << "; cached against traced: "
                << "mean |diff| " << sumDiff / std::max(sumTraced, 1e-9) << " of the mean, " << edgePixels
                << " pixels over 5%");
  // The scene has every case in numbers.
  REQUIRE(visible > 300);
  REQUIRE(offscreen > 50);
  REQUIRE(hidden > 30);
  CHECK(offDiffer == 0);
  CHECK(hiddenDiffer == 0);
  REQUIRE(visibleLit > 200);
  CHECK(visibleDarker >= visibleLit * 98 / 100);
  // Where read, the shadow image says what the ray would have: the cached image agrees with the traced one.
  CHECK(sumDiff <= kMeanRelativeTolerance * sumTraced);
  CHECK(edgePixels <= uint32_t(kEdgePixelShare * visible));
  // Every visible hit saved its shadow ray; which hits read does not depend on the image's values.
  CHECK(run.tracedStats.rays > run.cachedStats.rays);
  CHECK(saved >= visible);
  CHECK(saved <= floorPixels);
  CHECK(run.zeroStats.rays == run.cachedStats.rays);
}

TEST_CASE("mirror reflections trace their sun rays even with a shadow image", "[reflection][sun-cache]") {
  GpuFixture fx;
  Scene s;
  makeScene(s);
  const CpuGBuffer cpu = traceGBuffer(s.embree, s.view, {0.0f, 1.0f, 1.0f, 1.0f});
  const Runs run = runFrame(fx, s, cpu);
  size_t differ = 0;
  for (size_t i = 0; i < cpu.hit.size(); ++i) differ += !identical(run.traced, run.zero, i);
  CHECK(differ == 0);
  CHECK(run.tracedStats.rays > 0);
  CHECK(run.zeroStats.rays == run.tracedStats.rays);
  CHECK(run.cachedStats.rays == run.tracedStats.rays);
}

TEST_CASE("a sun visibility image of another size is refused by name", "[reflection][sun-cache][bad-input]") {
  GpuFixture fx;
  Scene s;
  makeScene(s);
  s.view.width = 32, s.view.height = 24;
  const CpuGBuffer cpu = traceGBuffer(s.embree, s.view, {kFloorRoughness, 1.0f, 1.0f, 1.0f});
  auto pass = rb::ReflectionPass::create(fx.ctx());
  RB_REQUIRE_OK(pass);
  rb::ReflectionSettings settings;
  settings.sunVisibilityMinRoughness = 1.5f;
  runPassFrame(
      fx, s.scene, cpu, true,
      [&](VkCommandBuffer cmd, const rb::GBufferDesc& g, const rb::TlasInfo& tlas) {
        rb::ReflectionFrame frame{.gbuffer = g, .tlas = tlas, .settings = {}};
        frame.sunVisibility = {.view = g.normal.view, .width = 16, .height = 12};
        rb::Status st = pass.value()->record(cmd, frame);
        REQUIRE(!st.ok());
        CHECK(st.error().message.find("ReflectionFrame::sunVisibility") != std::string::npos);
        frame.sunVisibility = {};
        frame.settings = settings;
        st = pass.value()->record(cmd, frame);
        REQUIRE(!st.ok());
        CHECK(st.error().message.find("sunVisibilityMinRoughness") != std::string::npos);
      },
      [](const rb::GBufferDesc&) {});
}

TEST_CASE("HybridEffects gives reflections the shadow effect's image unless disableSunFromScreen",
          "[reflection][sun-cache][hybrid]") {
  GpuFixture fx;
  EffectsRig rig(fx, 64, 48, 0.3f);  // every surface glossy, under the preset's roughness threshold
  auto rays = [&](bool disable) {
    rb::HybridEffectsDesc desc = rb::withPreset({}, rb::Preset::High);
    desc.reflections.roughnessThreshold = 1.0f;
    desc.reflections.disableSunFromScreen = disable;
    auto created = rb::HybridEffects::create(fx.ctx(), &rig.service(), desc);
    RB_REQUIRE_OK(created);
    for (int i = 0; i < 3; ++i) rig.record(*created.value());
    return created.value()->stats().reflection.rays;
  };
  const uint64_t traced = rays(true), cached = rays(false);
  INFO("reflection pass rays: every sun ray traced " << traced << ", read from the screen where it can " << cached);
  CHECK(cached > 0u);
  CHECK(cached < traced);
}
