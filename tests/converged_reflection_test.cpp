// Converged-tile skipping for denoised reflections (ReflectionSettings::schedule.convergedTiles), on lavapipe at 64x48:
// a static scene converges and then skips tiles, and the denoised output stays within a tolerance of the one without
// skipping; a camera that moves turns the view of the reflections, so their tiles are traced again, however slowly
// it moves, while a camera that only rotates keeps them; an object moved in the TLAS alone is re-traced in its
// reflection within the refresh period; bad settings are named. Each case runs two HybridEffects side by side in the
// same frames (the same rays), one skipping and one not.
#include <raybridge/raybridge.h>

#include <catch2/catch_test_macros.hpp>
#include <catch2/generators/catch_generators.hpp>
#include <glm/gtc/matrix_transform.hpp>

#include <algorithm>
#include <cmath>
#include <cstring>

#include "converged_pair.h"
#include "embree_reference.h"
#include "synthetic_gbuffer.h"
#include "test_scene.h"
#include "test_support.h"

using namespace rbtest;

namespace {

constexpr uint32_t kWidth = 64, kHeight = 48, kTile = 8;
// Fast convergence for a short test: 4 frames of history, relative noise under 10%, refreshed once in 4 frames.
constexpr uint32_t kMinFrames = 4, kRefresh = 4;
constexpr float kMaxNoise = 0.1f;
constexpr float kFloorRoughness = 0.2f;  // glossy: 4 rays a pixel, noisy
constexpr float kThreshold = 0.5f;       // the spheres (0.9) have no reflection

size_t tileOf(size_t pixel) {
  const size_t x = pixel % kWidth, y = pixel / kWidth;
  return (y / kTile) * ((kWidth + kTile - 1) / kTile) + x / kTile;
}

// The glossy ground, rough spheres (no reflection), a glossy box and a mirror box.
std::vector<float> sceneRoughness(size_t instances) {
  std::vector<float> r(instances, kFloorRoughness);
  r[1] = r[2] = 0.9f;
  r[4] = 0.0f;
  return r;
}

struct ReflectionPair {
  GpuFixture& fx;
  TestScene scene = makeConformanceScene();
  std::unique_ptr<EmbreeScene> embree = std::make_unique<EmbreeScene>();
  std::vector<float> roughness = sceneRoughness(scene.instances.size());
  CpuGBuffer cpu;
  SyntheticView view;
  std::unique_ptr<rb::AccelerationStructureService> service;
  BuiltScene built;
  std::unique_ptr<GpuGBuffer> gbuffer;
  std::unique_ptr<rb::HybridEffects> skipping, plain;
  rb::Light light;
  // `reorder`: the skipping one also asks for shader execution reordering (used where the context has it).
  explicit ReflectionPair(GpuFixture& f, uint32_t refreshPeriod = kRefresh, bool reorder = false) : fx(f) {
    addToEmbree(*embree, scene);
    setView(conformanceView(kWidth, kHeight));
    auto s = rb::AccelerationStructureService::create(fx.ctx());
    RB_REQUIRE_OK(s);
    service = std::move(s.value());
    built = buildScene(fx, *service, scene);
    rb::HybridEffectsDesc desc;
    desc.effects = rb::kEffectReflections;
    desc.reflections.raysPerPixel = 4;
    desc.reflections.roughnessThreshold = kThreshold;
    auto p = rb::HybridEffects::create(fx.ctx(), service.get(), desc);
    RB_REQUIRE_OK(p);
    plain = std::move(p.value());
    rb::ConvergedTileSettings& tiles = desc.reflections.schedule.convergedTiles;
    tiles.enabled = true;
    tiles.minFrames = kMinFrames;
    tiles.maxNoise = kMaxNoise;
    tiles.refreshPeriod = refreshPeriod;
    desc.reflections.invocationReorder = reorder;
    auto c = rb::HybridEffects::create(fx.ctx(), service.get(), desc);
    RB_REQUIRE_OK(c);
    skipping = std::move(c.value());
    light.direction[0] = 0.4f;
    light.direction[1] = 1.0f;
    light.direction[2] = 0.3f;
  }
  ~ReflectionPair() {
    skipping.reset();
    plain.reset();
    gbuffer.reset();
    destroyScene(fx, built);
  }
  void setView(const SyntheticView& v) {
    view = v;
    cpu = traceGBuffer(*embree, v, roughness);
    gbuffer = std::make_unique<GpuGBuffer>(fx, cpu);
  }
  // Moves instance `k` by (dx, 0, dz) in the instances the TLAS is rebuilt from each frame. The G-buffer stays: as
  // for an object the camera does not see directly, the pixels keep their surfaces and their history.
  void moveInstance(size_t k, float dx, float dz) {
    built.instances[k].transform[3] += dx;
    built.instances[k].transform[11] += dz;
  }
  void frame() {
    rb::HybridFrame f;
    f.gbuffer = gbuffer->desc();
    f.light = light;
    recordSideBySide(fx, *service, built, f, *skipping, *plain, true);  // reflections read shading records
  }
  std::vector<float> denoised(const rb::HybridEffects& e) {
    return readRgba16f(fx, e.outputs().reflection.image, kWidth, kHeight);
  }
  std::vector<float> raw(const rb::HybridEffects& e) {
    return readRgba16f(fx, e.outputs().reflectionRaw.image, kWidth, kHeight);
  }
  rb::PassStats stats(const rb::HybridEffects& e) const { return e.stats().reflection; }
  // The tiles with a kept-history mark (a = -1) in `raw`, and how many.
  static std::vector<uint8_t> markedTiles(const std::vector<float>& raw, size_t* count = nullptr) {
    std::vector<uint8_t> marked(size_t((kWidth + kTile - 1) / kTile) * ((kHeight + kTile - 1) / kTile), 0);
    for (size_t i = 0; i < size_t(kWidth) * kHeight; ++i)
      if (raw[i * 4 + 3] < -0.5f) marked[tileOf(i)] = 1;
    if (count) *count = size_t(std::count(marked.begin(), marked.end(), uint8_t(1)));
    return marked;
  }
};

// RMSE of the colours over the pixels `reference` covers, relative to their mean magnitude.
double relativeRmse(const std::vector<float>& a, const std::vector<float>& reference) {
  double sum = 0.0, magnitude = 0.0;
  size_t n = 0;
  for (size_t i = 0; i < size_t(kWidth) * kHeight; ++i) {
    if (reference[i * 4 + 3] < 0.5f) continue;
    for (int k = 0; k < 3; ++k) {
      const double e = double(a[i * 4 + k]) - reference[i * 4 + k];
      sum += e * e;
      magnitude += std::abs(double(reference[i * 4 + k]));
    }
    n += 3;
  }
  return n ? std::sqrt(sum / double(n)) / std::max(magnitude / double(n), 1e-6) : 0.0;
}

// Moves the camera sideways by `shift` (world units), target with it: every point's view direction turns.
SyntheticView shifted(SyntheticView v, double shift) {
  const glm::dvec3 side = glm::normalize(glm::cross(glm::normalize(v.target - v.eye), v.up));
  v.eye += side * shift;
  v.target += side * shift;
  return v;
}

}  // namespace

TEST_CASE("reflections: a static scene converges, then its converged tiles are skipped, and the denoised output "
          "stays within tolerance of the one without skipping",
          "[reflection][classifier][converged][denoise]") {
  // With shader execution reordering too: its own launch skips the converged tiles (where the device has it).
  const bool reorder = GENERATE(false, true);
  INFO("invocation reorder asked: " << reorder);
  GpuFixture fx;
  ReflectionPair p(fx, kRefresh, reorder);
  p.frame();
  CHECK(p.stats(*p.skipping).tilesConverged == 0);  // no history yet
  CHECK(p.stats(*p.skipping).rays == p.stats(*p.plain).rays);
  for (uint32_t i = 1; i < 12; ++i) {
    p.frame();
    if (i < kMinFrames) CHECK(p.stats(*p.skipping).tilesConverged == 0);
  }
  CHECK(p.skipping->reflectionPass()->reordered() == (reorder && fx.ctx().deviceInfo().invocationReorder));
  const rb::PassStats s = p.stats(*p.skipping), reference = p.stats(*p.plain);
  INFO("rays " << s.rays << " of " << reference.rays << " (saved " << s.raysSaved << "), converged tiles "
               << s.tilesConverged << " of " << s.tilesTotal());
  CHECK(s.tilesConverged * 4 >= s.tilesTotal());
  CHECK(s.raysSaved > 0);
  CHECK(double(s.rays) <= 0.8 * double(reference.rays));
  // Every tile is counted once: traced, or skipped (converged, or without a reflection).
  CHECK(s.tilesTotal() == (kWidth / kTile) * (kHeight / kTile));
  const std::vector<float> raw = p.raw(*p.skipping), skipped = p.denoised(*p.skipping), plain = p.denoised(*p.plain);
  size_t marks = 0;
  const std::vector<uint8_t> tiles = ReflectionPair::markedTiles(raw, &marks);
  CHECK(marks == s.tilesConverged);
  const std::vector<float> plainRaw = p.raw(*p.plain);
  for (size_t i = 0; i < size_t(kWidth) * kHeight; ++i) {
    // A marked pixel is one the plain pass covered; the rest of a marked tile holds the pass's own (0, 0, 0, 0).
    if (raw[i * 4 + 3] < -0.5f) REQUIRE(plainRaw[i * 4 + 3] == 1.0f);
    if (tiles[tileOf(i)] && raw[i * 4 + 3] > -0.5f) REQUIRE(raw[i * 4 + 3] == 0.0f);
    // The denoised image is complete: coverage as the plain pass's, finite colours.
    REQUIRE(skipped[i * 4 + 3] == plain[i * 4 + 3]);
    for (int k = 0; k < 3; ++k) REQUIRE(std::isfinite(skipped[i * 4 + k]));
  }
  const double e = relativeRmse(skipped, plain);
  INFO("denoised, skipping vs not: relative RMSE " << e);
  CHECK(e < 0.05);
}

TEST_CASE("reflections: a moving camera re-traces converged tiles, however slowly it moves; a rotating one does not",
          "[reflection][classifier][converged]") {
  GpuFixture fx;
  // No refresh within the test: only the view's turn makes a converged tile trace again.
  ReflectionPair p(fx, 1000);
  for (int i = 0; i < 10; ++i) p.frame();
  REQUIRE(p.stats(*p.skipping).tilesConverged > 0);

  SECTION("a rotation in place keeps the converged tiles") {
    SyntheticView v = p.view;
    const glm::dmat4 turn = glm::rotate(glm::dmat4(1.0), glm::radians(0.5), v.up);
    v.target = v.eye + glm::dvec3(turn * glm::dvec4(v.target - v.eye, 0.0));
    p.setView(v);
    p.frame();
    const rb::PassStats s = p.stats(*p.skipping);
    INFO("converged tiles after the rotation: " << s.tilesConverged << " of " << s.tilesTotal());
    CHECK(s.tilesConverged * 5 >= s.tilesTotal());
  }

  SECTION("a slow sideways move re-traces each converged tile once its view has turned far enough") {
    // 0.004 of the distance a frame turns the glossy ground's view near the target by about 0.1 of its lobe
    // (roughness 0.2: 0.08 rad wide), farther points less: under the quarter a skipped tile may turn in one frame.
    // On the CPU: each tile's turn summed over the frames (the largest of its covered pixels' each frame), in
    // lobe widths; a tile that has turned more than 0.3 (a margin over the quarter) must have been traced since.
    const double step = 0.004 * glm::length(p.view.target - p.view.eye);
    const std::vector<uint8_t> convergedBefore = ReflectionPair::markedTiles(p.raw(*p.skipping));
    std::vector<uint8_t> traced(convergedBefore.size(), 0);
    std::vector<double> turned(convergedBefore.size(), 0.0);
    size_t skippedAtFirst = 0, stale = 0, turnedFar = 0;
    double largestFirstTurn = 0.0;
    for (int i = 0; i < 8; ++i) {
      const glm::dvec3 from = p.view.eye;
      p.setView(shifted(p.view, step));
      std::vector<double> frameTurn(turned.size(), 0.0);
      for (size_t k = 0; k < size_t(kWidth) * kHeight; ++k) {
        if (!p.cpu.hit[k]) continue;  // the sky has no instance
        const float roughness = p.roughness[p.cpu.instance[k]];
        if (roughness > kThreshold) continue;
        const glm::dvec3 a = glm::normalize(p.cpu.position[k] - p.view.eye),
                         b = glm::normalize(p.cpu.position[k] - from);
        const double angle = std::atan2(glm::length(glm::cross(a, b)), glm::dot(a, b));
        const double lobe = std::max(2.0 * roughness * roughness, 2e-3);
        frameTurn[tileOf(k)] = std::max(frameTurn[tileOf(k)], angle / lobe);
      }
      p.frame();
      const std::vector<uint8_t> marked = ReflectionPair::markedTiles(p.raw(*p.skipping));
      for (size_t t = 0; t < marked.size(); ++t) {
        turned[t] += frameTurn[t];
        if (!marked[t]) {
          traced[t] = 1;
          turned[t] = 0.0;  // traced from this view: its drift starts again
        }
        if (i == 0 && marked[t]) {
          ++skippedAtFirst;
          largestFirstTurn = std::max(largestFirstTurn, frameTurn[t]);
        }
        if (convergedBefore[t] && turned[t] > 0.3) ++stale;  // skipped though it turned too far
      }
    }
    for (size_t t = 0; t < traced.size(); ++t) turnedFar += convergedBefore[t] && traced[t];
    INFO(skippedAtFirst << " tiles still skipped in the first frame of the move (largest turn " << largestFirstTurn
                        << " lobe widths); " << turnedFar << " converged tiles traced again; " << stale
                        << " skipped beyond 0.3 lobe widths of turn");
    CHECK(skippedAtFirst > 0);  // one small step is not enough to re-trace
    CHECK(largestFirstTurn < 0.25);
    CHECK(turnedFar > 0);  // the steps' sum is
    CHECK(stale == 0);
  }

  SECTION("a fast sideways move re-traces every tile at once") {
    p.setView(shifted(p.view, 0.05 * glm::length(p.view.target - p.view.eye)));
    p.frame();
    CHECK(p.stats(*p.skipping).tilesConverged == 0);
  }
}

TEST_CASE("reflections: an object moved in the TLAS alone is re-traced in its reflection within the refresh period",
          "[reflection][classifier][converged]") {
  GpuFixture fx;
  ReflectionPair p(fx);
  for (int i = 0; i < 10; ++i) p.frame();
  REQUIRE(p.stats(*p.skipping).tilesConverged > 0);
  // Before: the reference's raw colour over its last 6 frames.
  std::vector<float> before, since;
  for (int i = 0; i < 6; ++i) {
    p.frame();
    addToMean(before, p.raw(*p.plain), 6);
  }
  // The glossy box in front of the spheres slides away over the glossy ground, in the TLAS only: its reflection
  // leaves pixels whose G-buffer and history do not change, so only the refresh and its check can see it.
  p.moveInstance(3, -3.0f, 3.0f);
  size_t stale = 0;  // pixels of held tiles, whose stale history the denoiser drops
  for (uint32_t i = 0; i <= kRefresh; ++i) {
    p.frame();
    stale += staleMarks(p.raw(*p.skipping));
    addToMean(since, p.raw(*p.plain), kRefresh + 1);
  }
  const Retraced r = retracedPixels(before, since, p.raw(*p.plain), p.raw(*p.skipping));
  INFO(r.changed << " pixels whose reflection changed, " << r.caught << " traced again; " << stale
                 << " stale marks since the move");
  REQUIRE(r.changed > 10);
  CHECK(stale > 0);
  CHECK(r.caught * 20 >= r.changed * 19);
  // The denoised image follows the change at least as well as without skipping: both against the reference's raw
  // colour averaged over the frames since the move (noisy, but unbiased; the running means of both denoisers still
  // hold some of the old reflection, the held tiles' less, as their stale history was dropped).
  const std::vector<float> skippedDenoised = p.denoised(*p.skipping), plainDenoised = p.denoised(*p.plain);
  const double eSkipping = relativeRmse(skippedDenoised, since), ePlain = relativeRmse(plainDenoised, since);
  INFO("denoised after the move against the raw mean since: relative RMSE " << eSkipping << " skipping, " << ePlain
                                                                            << " not");
  CHECK(eSkipping <= 1.05 * ePlain);
}

TEST_CASE("bad reflection converged-tile settings are named", "[reflection][converged][bad_input]") {
  GpuFixture fx;
  auto pass = rb::ReflectionPass::create(fx.ctx());
  RB_REQUIRE_OK(pass);
  rb::DenoiserDesc scalarDesc;
  auto scalar = rb::Denoiser::create(fx.ctx(), scalarDesc);
  RB_REQUIRE_OK(scalar);
  rb::DenoiserDesc reflectionDesc;
  reflectionDesc.signal = rb::DenoiseSignal::Reflection;
  auto reflection = rb::Denoiser::create(fx.ctx(), reflectionDesc);
  RB_REQUIRE_OK(reflection);
  TestScene scene = makeConformanceScene();
  EmbreeScene embree;
  addToEmbree(embree, scene);
  const CpuGBuffer cpu = traceGBuffer(embree, conformanceView(kWidth, kHeight), sceneRoughness(scene.instances.size()));
  runPassFrame(
      fx, scene, cpu, true,
      [&](VkCommandBuffer cmd, const rb::GBufferDesc& desc, const rb::TlasInfo& tlas) {
        rb::ReflectionSettings s;
        s.schedule.convergedTiles.enabled = true;  // without the denoiser whose history it reads
        rb::Status st = pass.value()->record(cmd, {.gbuffer = desc, .tlas = tlas, .settings = s});
        REQUIRE(!st);
        CHECK(st.error().message.find("ReflectionSettings::schedule.history is nullptr") != std::string::npos);
        s.schedule.history = scalar.value().get();  // the wrong kind of history
        st = pass.value()->record(cmd, {.gbuffer = desc, .tlas = tlas, .settings = s});
        REQUIRE(!st);
        CHECK(st.error().message.find("history must be a DenoiseSignal::Reflection Denoiser") != std::string::npos);
        s.schedule.history = reflection.value().get();
        s.schedule.halfResolution = true;  // the tiles are of full-resolution pixels
        st = pass.value()->record(cmd, {.gbuffer = desc, .tlas = tlas, .settings = s});
        REQUIRE(!st);
        CHECK(st.error().message.find("disable halfResolution or convergedTiles") != std::string::npos);
        s.schedule.halfResolution = false;
        s.schedule.convergedTiles.maxNoise = -1.0f;
        st = pass.value()->record(cmd, {.gbuffer = desc, .tlas = tlas, .settings = s});
        REQUIRE(!st);
        CHECK(st.error().message.find("maxNoise") != std::string::npos);
      },
      [](const rb::GBufferDesc&) {});
  rb::HybridEffectsDesc d;
  d.effects = rb::kEffectReflections;
  d.reflections.schedule.convergedTiles.enabled = true;
  d.reflections.disableDenoiser = true;
  auto noDenoiser = rb::HybridEffects::create(fx.ctx(), nullptr, d);
  REQUIRE(!noDenoiser);
  CHECK(noDenoiser.error().message.find("HybridEffectsDesc::reflections.schedule.convergedTiles.enabled: converged "
                                        "tiles are read from the effect's denoiser's history") != std::string::npos);
  d.reflections.disableDenoiser = false;
  d.reflections.schedule.halfResolution = true;
  auto half = rb::HybridEffects::create(fx.ctx(), nullptr, d);
  REQUIRE(!half);
  CHECK(half.error().message.find("HybridEffectsDesc::reflections.schedule.convergedTiles skips tiles of "
                                  "full-resolution pixels: disable halfResolution or convergedTiles") !=
        std::string::npos);
}
