// Converged-tile skipping for denoised soft shadows (ShadowSettings::schedule.convergedTiles) and AO
// (AoSettings::schedule.convergedTiles), on lavapipe at 64x48: a static scene converges and then skips tiles (the rays
// saved are the rays missing); the denoised output stays within a tolerance of the one without skipping; a moved light
// is traced again within the refresh period; a camera move re-traces the tiles it disoccluded. Each case runs two
// HybridEffects side by side in the same frames (the same noise), one skipping and one not.
#include <raybridge/raybridge.h>

#include <catch2/catch_test_macros.hpp>
#include <catch2/generators/catch_generators.hpp>
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

enum class Effect { Shadows, Ao };
const char* effectName(Effect e) { return e == Effect::Ao ? "AO" : "soft shadows"; }

// The two effects (soft shadows, or AO) and the scene; frame() records both in one frame.
struct Pair {
  GpuFixture& fx;
  TestScene scene = makeConformanceScene();
  std::unique_ptr<EmbreeScene> embree = std::make_unique<EmbreeScene>();
  CpuGBuffer cpu;
  std::unique_ptr<rb::AccelerationStructureService> service;
  BuiltScene built;
  std::unique_ptr<GpuGBuffer> gbuffer;
  std::unique_ptr<rb::HybridEffects> skipping, plain;
  rb::Light light;
  Effect effect;
  // `adaptive`: both effects plan their rays from their denoiser's history (AdaptiveRaySettings defaults).
  explicit Pair(GpuFixture& f, Effect e = Effect::Shadows, bool adaptive = false) : fx(f), effect(e) {
    addToEmbree(*embree, scene);
    setView(conformanceView(kWidth, kHeight));
    auto s = rb::AccelerationStructureService::create(fx.ctx());
    RB_REQUIRE_OK(s);
    service = std::move(s.value());
    built = buildScene(fx, *service, scene);
    rb::HybridEffectsDesc desc;
    desc.effects = e == Effect::Ao ? rb::kEffectAo : rb::kEffectShadows;
    desc.shadows.raysPerPixel = 4;
    desc.ao.raysPerPixel = 4;
    desc.ao.range = 2.0f;
    desc.ao.schedule.adaptive.enabled = desc.shadows.schedule.adaptive.enabled = adaptive;
    auto p = rb::HybridEffects::create(fx.ctx(), service.get(), desc);
    RB_REQUIRE_OK(p);
    plain = std::move(p.value());
    rb::ConvergedTileSettings& tiles = e == Effect::Ao ? desc.ao.schedule.convergedTiles
                                                       : desc.shadows.schedule.convergedTiles;
    tiles.enabled = true;
    tiles.minFrames = kMinFrames;
    tiles.maxNoise = kMaxNoise;
    tiles.refreshPeriod = kRefresh;
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
    cpu = traceGBuffer(*embree, v);
    gbuffer = std::make_unique<GpuGBuffer>(fx, cpu);
  }
  // Moves instance `k` by (dx, 0, dz) in the TLAS, which is rebuilt. The G-buffer stays: as for an instance the
  // camera does not see (an engine's ray-only proxy), the pixels keep their surfaces and their history.
  void moveInstance(size_t k, float dx, float dz) {
    scene.instances[k].transform[3] += dx;
    scene.instances[k].transform[11] += dz;
    std::memcpy(built.instances[k].transform, scene.instances[k].transform.data(), sizeof(float) * 12);
    fx.runAndSettle([&](VkCommandBuffer cmd) {
      auto tlas = service->recordTlasBuild(cmd, built.instances, kRebuildTlas);
      RB_REQUIRE_OK(tlas);
      built.tlas = tlas.value();
    });
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
  std::vector<float> denoised(const rb::HybridEffects& e) {
    return readHalf(fx, effect == Effect::Ao ? e.outputs().ao.image : e.outputs().shadow.image);
  }
  std::vector<float> raw(const rb::HybridEffects& e) {
    return readHalf(fx, effect == Effect::Ao ? e.outputs().aoRaw.image : e.outputs().shadowRaw.image);
  }
  rb::PassStats stats(const rb::HybridEffects& e) const {
    return effect == Effect::Ao ? e.stats().ao : e.stats().shadow;
  }
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
          "the denoised output stays within tolerance of the one without skipping (soft shadows and AO)",
          "[shadow][ao][classifier][converged][denoise]") {
  const Effect effect = GENERATE(Effect::Shadows, Effect::Ao);
  INFO(effectName(effect));
  GpuFixture fx;
  Pair p(fx, effect);
  p.frame();
  const rb::PassStats first = p.stats(*p.skipping);
  CHECK(first.tilesConverged == 0);  // no history yet
  CHECK(first.rays == p.stats(*p.plain).rays);
  rb::PassStats last;
  for (uint32_t i = 1; i < 12; ++i) {
    p.frame();
    last = p.stats(*p.skipping);
    const rb::PassStats reference = p.stats(*p.plain);
    INFO("frame " << i << ": " << last.rays << " rays + " << last.raysSaved << " saved, reference " << reference.rays
                  << "; tiles converged " << last.tilesConverged << " of " << last.tilesTotal());
    // Uniform rays: a skipped tile's trace pixels would each have traced 4.
    CHECK(last.rays + last.raysSaved == reference.rays);
    if (i < kMinFrames) CHECK(last.tilesConverged == 0);
  }
  const uint64_t reference = p.stats(*p.plain).rays;
  INFO("rays " << last.rays << " of " << reference << ", converged tiles " << last.tilesConverged << " of "
               << last.tilesTotal());
  CHECK(last.tilesConverged * 4 >= last.tilesTotal());  // the conformance scene's lit and shadowed (open) floors
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

TEST_CASE("converged tiles with adaptive rays: the converged tiles trace nothing, the others what the plan says "
          "(soft shadows and AO)",
          "[shadow][ao][classifier][converged][adaptive]") {
  const Effect effect = GENERATE(Effect::Shadows, Effect::Ao);
  INFO(effectName(effect));
  GpuFixture fx;
  Pair p(fx, effect, true);
  for (int i = 0; i < 12; ++i) p.frame();
  const rb::PassStats s = p.stats(*p.skipping), reference = p.stats(*p.plain);
  INFO("rays " << s.rays << " (reference " << reference.rays << "), converged tiles " << s.tilesConverged << " of "
               << s.tilesTotal());
  CHECK(s.tilesConverged * 4 >= s.tilesTotal());
  CHECK(s.rays < reference.rays);
  // The adaptive launch over the tile list: a traced tile's pixels trace what the plan gives them (AO: exactly;
  // shadows: pixels facing away from the light trace none), a skipped tile's none.
  const std::vector<float> raw = p.raw(*p.skipping);
  const VkImage planImage = effect == Effect::Ao ? p.skipping->aoPass()->outputs().rayPlan
                                                 : p.skipping->shadowPass()->outputs().rayPlan;
  REQUIRE(planImage != VK_NULL_HANDLE);
  const std::vector<uint8_t> plan = readPassImage(fx, planImage, kWidth, kHeight, 4);
  size_t marks = 0;
  uint64_t planned = 0;
  for (size_t i = 0; i < raw.size(); ++i) {
    uint16_t half;
    std::memcpy(&half, plan.data() + 4 * i, 2);
    if (raw[i] < -0.5f) {
      ++marks;
    } else {
      planned += uint64_t(glm::unpackHalf1x16(half));
    }
  }
  CHECK(marks > 0);
  INFO(planned << " rays planned outside the skipped tiles");
  if (effect == Effect::Ao) {
    CHECK(s.rays == planned);
  } else {
    CHECK(s.rays <= planned);
  }
  const Difference d = difference(p.denoised(*p.skipping), p.denoised(*p.plain), p.cpu);
  INFO("denoised, skipping vs not: RMSE " << d.rmse << ", max " << d.max);
  CHECK(d.rmse < 0.03);
}

TEST_CASE("AO: a moved occluder is traced again within the refresh period", "[ao][classifier][converged]") {
  GpuFixture fx;
  Pair p(fx, Effect::Ao);
  // Before: the reference's raw AO summed over its last 6 frames (24 rays a pixel), to tell the open floor from
  // noise.
  std::vector<float> before(size_t(kWidth) * kHeight, 0.0f);
  for (int i = 0; i < 10; ++i) {
    p.frame();
    if (i < 4) continue;
    const std::vector<float> raw = p.raw(*p.plain);
    for (size_t k = 0; k < raw.size(); ++k) before[k] += raw[k] / 6.0f;
  }
  const uint64_t convergedBefore = p.stats(*p.skipping).tilesConverged;
  REQUIRE(convergedBefore > 0);
  // The box in front of the spheres slides 4.2 units across the open, converged floor, in the TLAS only: its contact
  // occlusion appears where the floor's history says 1, and the G-buffer and its history do not change, so only
  // the refresh and its check can see it.
  p.moveInstance(3, -3.0f, 3.0f);
  std::vector<float> since(before.size(), 0.0f);  // the reference's raw AO over the frames since the move
  for (uint32_t i = 0; i <= kRefresh; ++i) {
    p.frame();
    const std::vector<float> raw = p.raw(*p.plain);
    for (size_t k = 0; k < raw.size(); ++k) since[k] += raw[k] / float(kRefresh + 1);
  }
  const std::vector<float> after = p.raw(*p.plain), skipping = p.raw(*p.skipping);
  // Changed: open before (at least 23 of 24 rays), at most 60% open over the 20 rays since. Noise alone would
  // almost never do that; a single frame's noise in a converged tile can move a pixel by half, which is no change.
  size_t changed = 0, caught = 0;
  for (size_t i = 0; i < after.size(); ++i) {
    if (!p.cpu.hit[i] || before[i] < 0.95f || since[i] > 0.6f) continue;
    ++changed;
    caught += skipping[i] == after[i];  // traced this frame: the same rays as the reference's
  }
  INFO(changed << " open pixels occluded since, " << caught << " traced again; converged tiles " << convergedBefore
               << " before, " << p.stats(*p.skipping).tilesConverged << " after");
  // A tile is held once its refresh disagrees with its history beyond the rays' noise, summed over the tile: a tile
  // where one pixel changed by a little may pass (45 of 46 here; without the refresh or without the check, 0).
  REQUIRE(changed > 20);
  CHECK(caught * 10 >= changed * 9);
}

TEST_CASE("a camera move re-traces the tiles it disoccluded (soft shadows and AO)",
          "[shadow][ao][classifier][converged]") {
  const Effect effect = GENERATE(Effect::Shadows, Effect::Ao);
  INFO(effectName(effect));
  GpuFixture fx;
  Pair p(fx, effect);
  for (int i = 0; i < 10; ++i) p.frame();
  REQUIRE(p.stats(*p.skipping).tilesConverged > 0);
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
  const rb::PassStats s = p.stats(*p.skipping);
  INFO(disoccluded << " disoccluded pixels; " << marked << " tiles skipped, " << wrong
                   << " of them with a disoccluded pixel; stats: converged " << s.tilesConverged << " of "
                   << s.tilesTotal());
  REQUIRE(disoccluded > 0);
  CHECK(wrong == 0);
  CHECK(marked == s.tilesConverged);
  // Everything else is traced: the denoised images agree with the reference's as in a static scene. Not to the
  // pixel: the traced run's anti-lag trims a few histories at sharp shadow edges the move shifted by a fraction of a
  // pixel, which a skipped tile, with no new rays to compare, keeps (soft shadows: RMSE 0.024, 0.0046 with anti-lag
  // off in both runs; AO 0.0071 either way).
  const Difference d = difference(p.denoised(*p.skipping), p.denoised(*p.plain), p.cpu);
  INFO("denoised after the move: RMSE " << d.rmse << ", max " << d.max);
  CHECK(d.rmse < (effect == Effect::Shadows ? 0.035 : 0.02));
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
  s.schedule.convergedTiles.enabled = true;  // without the denoiser whose history it reads
  runPassFrame(
      fx, scene, cpu, false,
      [&](VkCommandBuffer cmd, const rb::GBufferDesc& desc, const rb::TlasInfo& tlas) {
        const rb::Status st =
            shadow.value()->record(cmd, {.gbuffer = desc, .tlas = tlas, .light = rb::Light{}, .settings = s});
        REQUIRE(!st);
        CHECK(st.error().message.find("ShadowSettings::schedule.history is nullptr") != std::string::npos);
      },
      [](const rb::GBufferDesc&) {});
}

TEST_CASE("bad AO converged-tile settings are named", "[ao][converged][bad_input]") {
  GpuFixture fx;
  auto ao = rb::AoPass::create(fx.ctx());
  RB_REQUIRE_OK(ao);
  auto denoiser = rb::Denoiser::create(fx.ctx());
  RB_REQUIRE_OK(denoiser);
  TestScene scene = makeConformanceScene();
  EmbreeScene embree;
  addToEmbree(embree, scene);
  const CpuGBuffer cpu = traceGBuffer(embree, conformanceView(kWidth, kHeight));
  runPassFrame(
      fx, scene, cpu, false,
      [&](VkCommandBuffer cmd, const rb::GBufferDesc& desc, const rb::TlasInfo& tlas) {
        rb::AoSettings s;
        s.schedule.convergedTiles.enabled = true;  // without the denoiser whose history it reads
        rb::Status st = ao.value()->record(cmd, {.gbuffer = desc, .tlas = tlas, .settings = s});
        REQUIRE(!st);
        CHECK(st.error().message.find("AoSettings::schedule.history is nullptr") != std::string::npos);
        s.schedule.history = denoiser.value().get();
        s.schedule.halfResolution = true;  // the tiles are of full-resolution pixels
        st = ao.value()->record(cmd, {.gbuffer = desc, .tlas = tlas, .settings = s});
        REQUIRE(!st);
        CHECK(st.error().message.find("disable halfResolution or convergedTiles") != std::string::npos);
      },
      [](const rb::GBufferDesc&) {});
  rb::HybridEffectsDesc d;
  d.effects = rb::kEffectAo;
  d.ao.schedule.convergedTiles.enabled = true;
  d.ao.disableDenoiser = true;
  auto noDenoiser = rb::HybridEffects::create(fx.ctx(), nullptr, d);
  REQUIRE(!noDenoiser);
  CHECK(noDenoiser.error().message.find("HybridEffectsDesc::ao.schedule.convergedTiles.enabled: converged tiles are "
                                        "read from the effect's denoiser's history") != std::string::npos);
  d.ao.disableDenoiser = false;
  d.ao.schedule.halfResolution = true;
  auto half = rb::HybridEffects::create(fx.ctx(), nullptr, d);
  REQUIRE(!half);
  CHECK(half.error().message.find("HybridEffectsDesc::ao.schedule.convergedTiles skips tiles of full-resolution "
                                  "pixels: disable halfResolution or convergedTiles") != std::string::npos);
}
