// Converged-tile skipping for denoised soft shadows (ShadowSettings::convergedTiles), on lavapipe at 64x48: a
// static scene converges and then skips tiles (the rays saved are the rays missing); the denoised shadows stay within
// a tolerance of those without skipping; a moved light is traced again within the refresh period; a camera move
// re-traces the tiles it disoccluded. Each case runs two HybridEffects side by side in the same frames (the same
// noise), one skipping and one not.
#include <raybridge/raybridge.h>

#include <catch2/catch_test_macros.hpp>
#include <glm/gtc/packing.hpp>

#include <algorithm>
#include <cmath>
#include <cstring>

#include "embree_reference.h"
#include "synthetic_gbuffer.h"
#include "test_scene.h"
#include "test_support.h"

using namespace rbtest;

namespace {

constexpr uint32_t kWidth = 64, kHeight = 48, kTile = 8;
// Fast convergence for a short test: 4 frames of history, noise under 0.1 (the fully lit and fully shadowed tiles;
// penumbrae at 4 rays need more frames), refreshed once in 4 frames.
constexpr uint32_t kMinFrames = 4, kRefresh = 4;
constexpr float kMaxNoise = 0.1f;

std::vector<float> readHalf(GpuFixture& fx, VkImage image) {
  std::vector<uint8_t> raw = readPassImage(fx, image, kWidth, kHeight, 2);
  std::vector<float> out(size_t(kWidth) * kHeight);
  for (size_t i = 0; i < out.size(); ++i) {
    uint16_t half;
    std::memcpy(&half, raw.data() + 2 * i, 2);
    out[i] = glm::unpackHalf1x16(half);
  }
  return out;
}

size_t tileOf(size_t pixel) {
  const size_t x = pixel % kWidth, y = pixel / kWidth;
  return (y / kTile) * ((kWidth + kTile - 1) / kTile) + x / kTile;
}

// The two effects and the scene; frame() records both in one frame.
struct Pair {
  GpuFixture& fx;
  TestScene scene = makeConformanceScene();
  EmbreeScene embree;
  CpuGBuffer cpu;
  std::unique_ptr<rb::AccelerationStructureService> service;
  BuiltScene built;
  std::unique_ptr<GpuGBuffer> gbuffer;
  std::unique_ptr<rb::HybridEffects> skipping, plain;
  rb::Light light;
  explicit Pair(GpuFixture& f) : fx(f) {
    addToEmbree(embree, scene);
    setView(conformanceView(kWidth, kHeight));
    auto s = rb::AccelerationStructureService::create(fx.ctx());
    RB_REQUIRE_OK(s);
    service = std::move(s.value());
    built = buildScene(fx, *service, scene);
    rb::HybridEffectsDesc desc;
    desc.effects = rb::kEffectShadows;
    desc.shadows.raysPerPixel = 4;
    auto p = rb::HybridEffects::create(fx.ctx(), service.get(), desc);
    RB_REQUIRE_OK(p);
    plain = std::move(p.value());
    desc.shadows.convergedTiles.enabled = true;
    desc.shadows.convergedTiles.minFrames = kMinFrames;
    desc.shadows.convergedTiles.maxNoise = kMaxNoise;
    desc.shadows.convergedTiles.refreshPeriod = kRefresh;
    auto c = rb::HybridEffects::create(fx.ctx(), service.get(), desc);
    RB_REQUIRE_OK(c);
    skipping = std::move(c.value());
    light.direction[0] = 0.4f;
    light.direction[1] = 1.0f;
    light.direction[2] = 0.3f;
    light.angularRadiusDegrees = 4.0f;  // soft
  }
  ~Pair() {
    skipping.reset();
    plain.reset();
    gbuffer.reset();
    destroyScene(fx, built);
  }
  void setView(const SyntheticView& v) {
    cpu = traceGBuffer(embree, v);
    gbuffer = std::make_unique<GpuGBuffer>(fx, cpu);
  }
  void frame() {
    rb::HybridFrame f;
    f.gbuffer = gbuffer->desc();
    f.tlas = &built.tlas;
    f.light = light;
    fx.runAndSettle([&](VkCommandBuffer cmd) {
      RB_REQUIRE_OK(skipping->record(cmd, f));
      RB_REQUIRE_OK(plain->record(cmd, f));
    });
  }
  std::vector<float> denoised(const rb::HybridEffects& e) { return readHalf(fx, e.outputs().shadow.image); }
  std::vector<float> raw(const rb::HybridEffects& e) { return readHalf(fx, e.outputs().shadowRaw.image); }
};

// Root mean square and largest difference over surface pixels.
struct Difference {
  double rmse = 0.0, max = 0.0;
};
Difference difference(const std::vector<float>& a, const std::vector<float>& b, const CpuGBuffer& cpu) {
  Difference d;
  size_t n = 0;
  for (size_t i = 0; i < a.size(); ++i) {
    if (!cpu.hit[i]) continue;
    const double e = double(a[i]) - b[i];
    d.rmse += e * e;
    d.max = std::max(d.max, std::abs(e));
    ++n;
  }
  d.rmse = n ? std::sqrt(d.rmse / double(n)) : 0.0;
  return d;
}

}  // namespace

TEST_CASE("a static scene converges, then its converged tiles are skipped: the rays saved are the rays missing, and "
          "the denoised shadows stay within tolerance of those without skipping",
          "[shadow][classifier][converged][denoise]") {
  GpuFixture fx;
  Pair p(fx);
  p.frame();
  const rb::PassStats first = p.skipping->stats().shadow;
  CHECK(first.tilesConverged == 0);  // no history yet
  CHECK(first.rays == p.plain->stats().shadow.rays);
  rb::PassStats last;
  for (uint32_t i = 1; i < 12; ++i) {
    p.frame();
    last = p.skipping->stats().shadow;
    const rb::PassStats reference = p.plain->stats().shadow;
    INFO("frame " << i << ": " << last.rays << " rays + " << last.raysSaved << " saved, reference " << reference.rays
                  << "; tiles converged " << last.tilesConverged << " of " << last.tilesTotal());
    // Uniform rays: a skipped tile's trace pixels would each have traced 4.
    CHECK(last.rays + last.raysSaved == reference.rays);
    if (i < kMinFrames) CHECK(last.tilesConverged == 0);
  }
  const uint64_t reference = p.plain->stats().shadow.rays;
  INFO("rays " << last.rays << " of " << reference << ", converged tiles " << last.tilesConverged << " of "
               << last.tilesTotal());
  CHECK(last.tilesConverged * 4 >= last.tilesTotal());  // the conformance scene's lit and shadowed floors
  CHECK(double(last.rays) <= 0.8 * double(reference));
  // The pixels of skipped tiles carry kept-history marks; the denoised image has none.
  const std::vector<float> raw = p.raw(*p.skipping), skipped = p.denoised(*p.skipping), plain = p.denoised(*p.plain);
  size_t marks = 0;
  for (float v : raw) marks += v < -0.5f;
  CHECK(marks > 0);
  for (float v : skipped) REQUIRE((v >= 0.0f && v <= 1.0f));
  const Difference d = difference(skipped, plain, p.cpu);
  INFO("denoised, skipping vs not: RMSE " << d.rmse << ", max " << d.max);
  CHECK(d.rmse < 0.02);
  CHECK(d.max < 0.15);
}

TEST_CASE("a moved light is traced again within the refresh period", "[shadow][classifier][converged]") {
  GpuFixture fx;
  Pair p(fx);
  for (int i = 0; i < 10; ++i) p.frame();
  const std::vector<float> before = p.raw(*p.plain);
  const uint64_t convergedBefore = p.skipping->stats().shadow.tilesConverged;
  REQUIRE(convergedBefore > 0);
  // The sun swings to the other side: shadows move across converged (skipped) tiles.
  p.light.direction[0] = -0.5f;
  p.light.direction[2] = -0.2f;
  for (uint32_t i = 0; i <= kRefresh; ++i) p.frame();
  // Every pixel whose shadow flipped is traced again: its raw visibility is the reference's, this frame's rays.
  const std::vector<float> after = p.raw(*p.plain), skipping = p.raw(*p.skipping);
  size_t flipped = 0, caught = 0;
  for (size_t i = 0; i < after.size(); ++i) {
    if (!p.cpu.hit[i] || std::abs(after[i] - before[i]) < 0.99f) continue;
    ++flipped;
    caught += skipping[i] == after[i];
  }
  INFO(flipped << " pixels flipped, " << caught << " traced again; converged tiles " << convergedBefore << " before, "
               << p.skipping->stats().shadow.tilesConverged << " after");
  REQUIRE(flipped > 20);
  CHECK(caught == flipped);
}

TEST_CASE("a camera move re-traces the tiles it disoccluded", "[shadow][classifier][converged]") {
  GpuFixture fx;
  Pair p(fx);
  for (int i = 0; i < 10; ++i) p.frame();
  REQUIRE(p.skipping->stats().shadow.tilesConverged > 0);
  const CpuGBuffer old = p.cpu;
  SyntheticView v = old.view;
  const glm::dvec3 forward = glm::normalize(v.target - v.eye);
  const glm::dvec3 side = glm::normalize(glm::cross(forward, v.up));
  const double shift = 0.08 * glm::length(v.target - v.eye);
  v.eye += side * shift;
  v.target += side * shift;
  p.setView(v);
  p.frame();
  // Disoccluded on the CPU: a surface pixel whose point is off the old image, or lands on sky or on a surface more
  // than 10% of its distance away (the denoiser's own test is 2%: pixels in between are not asserted).
  const std::vector<float> raw = p.raw(*p.skipping);
  const size_t tiles = size_t((kWidth + kTile - 1) / kTile) * ((kHeight + kTile - 1) / kTile);
  std::vector<uint8_t> disoccludedTile(tiles, 0), markedTile(tiles, 0);
  size_t disoccluded = 0;
  for (size_t i = 0; i < raw.size(); ++i) {
    if (raw[i] < -0.5f) markedTile[tileOf(i)] = 1;
    if (!p.cpu.hit[i]) continue;
    const glm::dvec3 world = p.cpu.position[i];
    const glm::vec4 clip = old.projection * old.viewMatrix * glm::vec4(glm::vec3(world - old.view.eye), 1.0f);
    const glm::vec2 at = (glm::vec2(clip) / clip.w * 0.5f + 0.5f) * glm::vec2(kWidth, kHeight);
    bool seen = false;
    if (clip.w > 0.0f && at.x >= 0.0f && at.y >= 0.0f && at.x < kWidth && at.y < kHeight) {
      const size_t o = size_t(at.y) * kWidth + size_t(at.x);
      const double dist = glm::length(world - old.view.eye);
      seen = old.hit[o] && glm::length(old.position[o] - world) <= 0.1 * dist;
    }
    if (!seen) {
      ++disoccluded;
      disoccludedTile[tileOf(i)] = 1;
    }
  }
  size_t wrong = 0, marked = 0;
  for (size_t t = 0; t < tiles; ++t) {
    marked += markedTile[t];
    wrong += markedTile[t] && disoccludedTile[t];
  }
  const rb::PassStats s = p.skipping->stats().shadow;
  INFO(disoccluded << " disoccluded pixels; " << marked << " tiles skipped, " << wrong
                   << " of them with a disoccluded pixel; stats: converged " << s.tilesConverged << " of "
                   << s.tilesTotal());
  REQUIRE(disoccluded > 0);
  CHECK(wrong == 0);
  CHECK(marked == s.tilesConverged);
  // Everything else is traced: the denoised images agree with the reference's as in a static scene.
  const Difference d = difference(p.denoised(*p.skipping), p.denoised(*p.plain), p.cpu);
  INFO("denoised after the move: RMSE " << d.rmse << ", max " << d.max);
  CHECK(d.rmse < 0.02);
}

TEST_CASE("bad converged-tile settings are named", "[shadow][converged][bad_input]") {
  GpuFixture fx;
  auto shadow = rb::ShadowPass::create(fx.ctx());
  RB_REQUIRE_OK(shadow);
  TestScene scene = makeConformanceScene();
  EmbreeScene embree;
  addToEmbree(embree, scene);
  const CpuGBuffer cpu = traceGBuffer(embree, conformanceView(kWidth, kHeight));
  rb::ShadowSettings s;
  s.convergedTiles.enabled = true;  // without the denoiser whose history it reads
  runPassFrame(
      fx, scene, cpu, false,
      [&](VkCommandBuffer cmd, const rb::GBufferDesc& desc, const rb::TlasInfo& tlas) {
        const rb::Status st = shadow.value()->record(cmd, desc, tlas, rb::Light{}, s);
        REQUIRE(!st);
        CHECK(st.error().message.find("ShadowSettings::convergedTiles: history is nullptr") != std::string::npos);
      },
      [](const rb::GBufferDesc&) {});
}
