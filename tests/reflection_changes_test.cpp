// ReflectionSettings::changedBoxes and relitBoxes: a reflection shows changes its own surface does not (a lamp that
// moved, seen in a mirror). On a mirror floor in front of a box, the pixels whose reflection ray meets a changed box
// are marked stale (a = 2), exactly those Embree says, and the Reflection denoiser restarts exactly their history.
#include <catch2/catch_test_macros.hpp>

#include <glm/glm.hpp>
#include <glm/gtc/packing.hpp>

#include <cstring>
#include <functional>
#include <string>

#include "synthetic_gbuffer.h"

using namespace rbtest;

namespace {

constexpr uint32_t kW = 96, kH = 72;

struct MirrorScene {
  TestScene scene;
  std::vector<rb::Material> materials = std::vector<rb::Material>(2);
  EmbreeScene embree;
  SyntheticView view;
  CpuGBuffer cpu;
  rb::ChangedBox box;  // the box instance's world box
  MirrorScene() {
    scene.meshes.push_back(rbsamples::makeGrid(12.0f, 12));
    const float mn[3] = {-0.6f, 0.0f, -0.6f}, mx[3] = {0.6f, 1.5f, 0.6f};
    scene.meshes.push_back(rbsamples::makeBox(mn, mx, 2));
    scene.instances.push_back({0, translation(0, 0, 0), 0});
    scene.instances.push_back({1, translation(0, 0, -1.5f), 1});
    addToEmbree(embree, scene);
    view.eye = {0.3, 1.2, 4.0};
    view.target = {0.0, 0.2, -1.0};
    view.width = kW;
    view.height = kH;
    cpu = traceGBuffer(embree, view, {0.0f, 1.0f});  // floor a mirror, box rough (no reflection rays)
    box.min[0] = -0.6, box.min[1] = 0.0, box.min[2] = -2.1;
    box.max[0] = 0.6, box.max[1] = 1.5, box.max[2] = -0.9;
  }
  // Where the mirror ray of floor pixel i goes: the instance it hits, -1 for the sky.
  int mirrorHit(size_t i) const {
    glm::dvec3 v = glm::normalize(cpu.position[i] - view.eye);
    glm::dvec3 r = glm::reflect(v, glm::dvec3(0, 1, 0));
    glm::dvec3 o = cpu.position[i] + glm::dvec3(0, 1e-4, 0);
    float of[3] = {float(o.x), float(o.y), float(o.z)}, d[3] = {float(r.x), float(r.y), float(r.z)};
    ReferenceHit h = embree.intersect(of, d, 0.0f, 1e30f);
    return h.hit ? int(h.instanceId) : -1;
  }
  // A floor pixel whose 3x3 neighbours all see the floor and reflect the same thing (no edge to round either way).
  bool interior(uint32_t x, uint32_t y) const {
    if (x == 0 || y == 0 || x + 1 >= kW || y + 1 >= kH) return false;
    const int target = mirrorHit(size_t(y) * kW + x);
    for (int dy = -1; dy <= 1; ++dy)
      for (int dx = -1; dx <= 1; ++dx) {
        const size_t j = size_t(int(y) + dy) * kW + size_t(int(x) + dx);
        if (!cpu.hit[j] || cpu.instance[j] != 0 || mirrorHit(j) != target) return false;
      }
    return true;
  }
};

rb::ReflectionSettings mirrorSettings() {
  rb::ReflectionSettings s;
  // A sun from behind the camera: the box's own shadow falls away from the mirror's view of it.
  s.lighting.sunDirection[0] = 0.3f;
  s.lighting.sunDirection[1] = 1.0f;
  s.lighting.sunDirection[2] = 0.6f;
  return s;
}

// One frame of the pass (and the Reflection denoiser when given); the output's alpha per pixel.
std::vector<float> passAlpha(GpuFixture& fx, const MirrorScene& m, rb::ReflectionPass& pass,
                             const rb::ReflectionSettings& settings, rb::Denoiser* denoiser = nullptr) {
  std::vector<float> alpha;
  runPassFrame(
      fx, m.scene, m.cpu, true,
      [&](VkCommandBuffer cmd, const rb::GBufferDesc& desc, const rb::TlasInfo& tlas) {
        RB_REQUIRE_OK(pass.record(cmd, {.gbuffer = desc, .tlas = tlas, .settings = settings}));
        if (denoiser) RB_REQUIRE_OK(denoiser->record(cmd, {.gbuffer = desc, .signal = pass.outputs().radianceView}));
      },
      [&](const rb::GBufferDesc& desc) {
        std::vector<uint8_t> raw = readPassImage(fx, pass.outputs().radiance, desc.width, desc.height, 8);
        alpha.resize(size_t(desc.width) * desc.height);
        for (size_t i = 0; i < alpha.size(); ++i) {
          uint16_t h;
          std::memcpy(&h, raw.data() + 8 * i + 6, 2);
          alpha[i] = glm::unpackHalf1x16(h);
        }
      });
  return alpha;
}

}  // namespace

TEST_CASE("reflection rays that meet a changed box mark their pixel stale, exactly where Embree says",
          "[reflection][changes][embree]") {
  GpuFixture fx;
  const MirrorScene m;
  auto pass = rb::ReflectionPass::create(fx.ctx());
  RB_REQUIRE_OK(pass);
  RB_REQUIRE_OK(pass.value()->setMaterials(m.materials, {}));
  // box: the box instance moved (its path tested); lit: the box's surroundings relit (hit points tested); aside: a
  // change no reflection ray reaches (nothing marked).
  rb::ChangedBox aside;
  aside.min[0] = 4.0, aside.min[1] = 0.0, aside.min[2] = 3.0;
  aside.max[0] = 5.0, aside.max[1] = 1.0, aside.max[2] = 4.0;
  rb::ChangedBox lit = m.box;
  for (int a = 0; a < 3; ++a) lit.min[a] -= 0.05, lit.max[a] += 0.05;
  struct Case {
    const char* name;
    std::function<void(rb::ReflectionSettings&)> give;
    bool marksBox;  // the pixels that reflect the box are stale
  };
  const Case cases[] = {
      {"changed box", [&](rb::ReflectionSettings& s) { s.changedBoxes = std::span(&m.box, 1); }, true},
      {"relit box", [&](rb::ReflectionSettings& s) { s.relitBoxes = std::span(&lit, 1); }, true},
      {"a change aside", [&](rb::ReflectionSettings& s) { s.changedBoxes = std::span(&aside, 1); }, false},
      {"none", [](rb::ReflectionSettings&) {}, false},
  };
  for (const Case& c : cases) {
    DYNAMIC_SECTION(c.name) {
      rb::ReflectionSettings settings = mirrorSettings();
      c.give(settings);
      const std::vector<float> alpha = passAlpha(fx, m, *pass.value(), settings);
      uint32_t boxPixels = 0, skyPixels = 0, wrong = 0, stale = 0;
      for (uint32_t y = 0; y < kH; ++y)
        for (uint32_t x = 0; x < kW; ++x) {
          const size_t i = size_t(y) * kW + x;
          stale += alpha[i] > 1.5f;
          if (!m.interior(x, y)) continue;
          const int target = m.mirrorHit(i);
          (target == 1 ? boxPixels : skyPixels)++;
          const float expected = c.marksBox && target == 1 ? 2.0f : 1.0f;
          if (alpha[i] != expected && wrong++ < 5)
            UNSCOPED_INFO("pixel " << x << "," << y << " reflects " << target << ": a = " << alpha[i] << ", expected "
                                   << expected);
        }
      INFO(boxPixels << " interior pixels reflect the box, " << skyPixels << " the sky; " << stale << " stale");
      REQUIRE(boxPixels > 100);
      REQUIRE(skyPixels > 100);
      CHECK(wrong == 0);
      if (!c.marksBox) CHECK(stale == 0);
    }
  }
}

TEST_CASE("the Reflection denoiser restarts the history of exactly the pixels marked stale",
          "[reflection][changes][denoise]") {
  GpuFixture fx;
  const MirrorScene m;
  auto pass = rb::ReflectionPass::create(fx.ctx());
  RB_REQUIRE_OK(pass);
  RB_REQUIRE_OK(pass.value()->setMaterials(m.materials, {}));
  auto denoiser = rb::Denoiser::create(fx.ctx(), rb::DenoiserDesc{rb::DenoiseSignal::Reflection});
  RB_REQUIRE_OK(denoiser);
  const rb::ReflectionSettings still = mirrorSettings();
  for (int f = 0; f < 3; ++f) passAlpha(fx, m, *pass.value(), still, denoiser.value().get());
  const std::vector<float> before = historyFrames(fx, *denoiser.value());
  rb::ReflectionSettings changed = still;
  changed.changedBoxes = std::span(&m.box, 1);
  const std::vector<float> alpha = passAlpha(fx, m, *pass.value(), changed, denoiser.value().get());
  const std::vector<float> after = historyFrames(fx, *denoiser.value());
  uint32_t stale = 0, kept = 0, wrong = 0;
  for (size_t i = 0; i < alpha.size(); ++i) {
    if (!m.cpu.hit[i] || m.cpu.instance[i] != 0 || alpha[i] < 0.5f) continue;  // mirror pixels that traced
    const bool s = alpha[i] > 1.5f;
    (s ? stale : kept)++;
    const float expected = s ? 1.0f : before[i] + 1.0f;
    if (after[i] != expected && wrong++ < 5)
      UNSCOPED_INFO("pixel " << i % kW << "," << i / kW << (s ? " (stale)" : "") << ": " << after[i]
                             << " frames, expected " << expected);
  }
  INFO(stale << " stale and " << kept << " kept mirror pixels");
  REQUIRE(stale > 100);
  REQUIRE(kept > 100);
  CHECK(wrong == 0);
}

TEST_CASE("changed boxes that are not boxes, or too many, are refused by name", "[reflection][changes][bad-input]") {
  GpuFixture fx;
  const MirrorScene m;
  auto pass = rb::ReflectionPass::create(fx.ctx());
  RB_REQUIRE_OK(pass);
  rb::ChangedBox inverted = m.box;
  inverted.min[1] = 2.0;  // above max
  rb::ChangedBox nan = m.box;
  nan.max[2] = std::nan("");
  const std::vector<rb::ChangedBox> many(rb::kMaxReflectionChangedBoxes + 1, m.box);
  struct Case {
    std::function<void(rb::ReflectionSettings&)> give;
    const char* expected;
  };
  const Case cases[] = {
      {[&](rb::ReflectionSettings& s) { s.changedBoxes = std::span(&inverted, 1); },
       "ReflectionSettings::changedBoxes[0] is not a box"},
      {[&](rb::ReflectionSettings& s) { s.relitBoxes = std::span(&nan, 1); },
       "ReflectionSettings::relitBoxes[0] is not a box"},
      {[&](rb::ReflectionSettings& s) { s.changedBoxes = many; },
       "ReflectionSettings::changedBoxes and relitBoxes hold 257 boxes, more than kMaxReflectionChangedBoxes (256)"},
  };
  for (const Case& c : cases) {
    rb::ReflectionSettings settings = mirrorSettings();
    c.give(settings);
    runPassFrame(
        fx, m.scene, m.cpu, true,
        [&](VkCommandBuffer cmd, const rb::GBufferDesc& desc, const rb::TlasInfo& tlas) {
          const rb::Status st = pass.value()->record(cmd, {.gbuffer = desc, .tlas = tlas, .settings = settings});
          REQUIRE_FALSE(st);
          INFO(st.error().message);
          CHECK(st.error().message.find(c.expected) != std::string::npos);
        },
        [](const rb::GBufferDesc&) {});
  }
}
