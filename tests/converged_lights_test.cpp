// Converged-tile skipping for denoised local lights (ManyLightSettings::schedule.convergedTiles, through
// HybridEffects), on lavapipe at 64x48 in the many-light room: a still scene converges and then skips tiles, and the
// denoised output stays within a tolerance of the one without skipping; a light moved while the tiles are converged is
// traced again within the refresh period; bad settings are named. Two HybridEffects run side by side in the same frames
// (the same rays), one skipping and one not.
#include <raybridge/raybridge.h>

#include <catch2/catch_test_macros.hpp>
#include <glm/glm.hpp>

#include <cmath>

#include "converged_pair.h"
#include "many_light_scene.h"

using namespace rbtest;

namespace {

constexpr uint32_t kWidth = 64, kHeight = 48, kTile = 8;
// Fast convergence for a short test: 4 frames of history, relative noise under 10%, refreshed once in 4 frames.
constexpr uint32_t kMinFrames = 4, kRefresh = 4;
constexpr float kMaxNoise = 0.1f;

struct LightsPair {
  GpuFixture& fx;
  TestScene scene = makeRoom();
  EmbreeScene embree;
  CpuGBuffer cpu;
  std::unique_ptr<rb::AccelerationStructureService> service;
  BuiltScene built;
  std::unique_ptr<GpuGBuffer> gbuffer;
  std::unique_ptr<rb::HybridEffects> skipping, plain;
  std::vector<rb::LightSource> lights = roomLights();
  // changeResets = false: a moved light is not a change HybridEffects knows of (hybrid_effects.h, "Change resets"),
  // so only the converged tiles' own refresh and stale marks catch it: what the refresh test checks.
  explicit LightsPair(GpuFixture& f, bool changeResets = true) : fx(f) {
    addToEmbree(embree, scene);
    cpu = traceGBuffer(embree, roomView(kWidth, kHeight));
    gbuffer = std::make_unique<GpuGBuffer>(fx, cpu);
    auto s = rb::AccelerationStructureService::create(fx.ctx());
    RB_REQUIRE_OK(s);
    service = std::move(s.value());
    built = buildScene(fx, *service, scene);
    rb::HybridEffectsDesc desc;
    desc.effects = rb::kEffectLocalLights;
    desc.localLights.raysPerPixel = 2;
    desc.disableChangeResets = !changeResets;
    auto p = rb::HybridEffects::create(fx.ctx(), service.get(), desc);
    RB_REQUIRE_OK(p);
    plain = std::move(p.value());
    rb::ConvergedTileSettings& tiles = desc.localLights.schedule.convergedTiles;
    tiles.enabled = true;
    tiles.minFrames = kMinFrames;
    tiles.maxNoise = kMaxNoise;
    tiles.refreshPeriod = kRefresh;
    auto c = rb::HybridEffects::create(fx.ctx(), service.get(), desc);
    RB_REQUIRE_OK(c);
    skipping = std::move(c.value());
  }
  ~LightsPair() {
    skipping.reset();
    plain.reset();
    gbuffer.reset();
    destroyScene(fx, built);
  }
  void frame() {
    rb::HybridFrame f;
    f.gbuffer = gbuffer->desc();
    f.localLights = lights;
    recordSideBySide(fx, *service, built, f, *skipping, *plain, false);
  }
  std::vector<float> raw(const rb::HybridEffects& e) {
    return readRgba16f(fx, e.outputs().localLightsRaw.image, kWidth, kHeight);
  }
  std::vector<float> denoised(const rb::HybridEffects& e) {
    return readRgba16f(fx, e.outputs().localLights.image, kWidth, kHeight);
  }
  rb::PassStats stats(const rb::HybridEffects& e) const { return e.stats().localLights; }
  std::vector<uint8_t> surface() const { return {cpu.hit.begin(), cpu.hit.end()}; }
};

}  // namespace

TEST_CASE("local lights: a still scene converges, then its converged tiles are skipped, and the denoised output "
          "stays within tolerance of the one without skipping",
          "[many_lights][classifier][converged][denoise]") {
  GpuFixture fx;
  LightsPair p(fx);
  p.frame();
  CHECK(p.stats(*p.skipping).tilesConverged == 0);  // no history yet
  CHECK(p.stats(*p.skipping).rays == p.stats(*p.plain).rays);
  for (uint32_t i = 1; i < 12; ++i) {
    p.frame();
    if (i < kMinFrames) CHECK(p.stats(*p.skipping).tilesConverged == 0);
  }
  const rb::PassStats s = p.stats(*p.skipping), reference = p.stats(*p.plain);
  INFO("rays " << s.rays << " of " << reference.rays << " (saved " << s.raysSaved << "), converged tiles "
               << s.tilesConverged << " of " << s.tilesTotal());
  CHECK(s.tilesTotal() == (kWidth / kTile) * (kHeight / kTile));
  CHECK(s.tilesConverged * 4 >= s.tilesTotal());
  CHECK(s.raysSaved > 0);
  CHECK(double(s.rays) <= 0.8 * double(reference.rays));
  // Kept-history marks where tiles were skipped; the denoised image is complete and close to the reference's.
  const std::vector<float> raw = p.raw(*p.skipping), skipped = p.denoised(*p.skipping), plain = p.denoised(*p.plain);
  size_t marks = 0;
  for (size_t i = 0; i < size_t(kWidth) * kHeight; ++i) {
    marks += raw[i * 4 + 3] < -0.5f;
    for (int k = 0; k < 4; ++k) REQUIRE(std::isfinite(skipped[i * 4 + k]));
    REQUIRE(skipped[i * 4 + 3] == 1.0f);
  }
  CHECK(marks > 0);
  const double e = relativeRmse(skipped, plain, p.surface());
  INFO("denoised, skipping vs not: relative RMSE " << e);
  CHECK(e < 0.03);
}

TEST_CASE("local lights: a light moved over converged tiles is traced again within the refresh period",
          "[many_lights][classifier][converged]") {
  GpuFixture fx;
  LightsPair p(fx, /*changeResets=*/false);
  for (int i = 0; i < 10; ++i) p.frame();
  REQUIRE(p.stats(*p.skipping).tilesConverged > 0);
  std::vector<float> before, since;  // the reference's raw irradiance over 6 frames before the move, and after it
  for (int i = 0; i < 6; ++i) {
    p.frame();
    addToMean(before, p.raw(*p.plain), 6);
  }
  // The first point light jumps across the room: the irradiance changes where the tiles' history says otherwise.
  glm::dvec3 moved(p.lights[0].light.position[0], p.lights[0].light.position[1], p.lights[0].light.position[2]);
  moved.x = -moved.x;
  moved.z += 2.0;
  for (int i = 0; i < 3; ++i) p.lights[0].light.position[i] = moved[i];
  size_t stale = 0;
  for (uint32_t i = 0; i <= kRefresh; ++i) {
    p.frame();
    stale += staleMarks(p.raw(*p.skipping));
    addToMean(since, p.raw(*p.plain), kRefresh + 1);
  }
  const Retraced r = retracedPixels(before, since, p.raw(*p.plain), p.raw(*p.skipping));
  INFO(r.changed << " pixels whose irradiance changed, " << r.caught << " traced again; " << stale
                 << " stale marks since the move");
  REQUIRE(r.changed > 20);
  CHECK(r.caught * 20 >= r.changed * 19);
  CHECK(stale > 0);
}

TEST_CASE("local lights: with change resets, a moved light's converged tiles are traced on the move's own frame",
          "[many_lights][classifier][converged][changes]") {
  GpuFixture fx;
  LightsPair p(fx);
  for (int i = 0; i < 10; ++i) p.frame();
  REQUIRE(p.stats(*p.skipping).tilesConverged > 0);
  std::vector<float> before, after;
  for (int i = 0; i < 6; ++i) {
    p.frame();
    addToMean(before, p.raw(*p.plain), 6);
  }
  REQUIRE(p.stats(*p.skipping).tilesConverged > 0);  // tiles are being skipped when the light moves
  p.lights[0].light.position[0] = -p.lights[0].light.position[0];
  p.lights[0].light.position[2] += 2.0;
  p.frame();
  addToMean(after, p.raw(*p.plain), 1);
  const Retraced r = retracedPixels(before, after, p.raw(*p.plain), p.raw(*p.skipping));
  INFO(r.changed << " pixels whose irradiance changed, " << r.caught << " traced on the move's frame");
  REQUIRE(r.changed > 20);
  CHECK(r.caught * 20 >= r.changed * 19);
  CHECK(p.skipping->changeMask(rb::kEffectLocalLights).image != VK_NULL_HANDLE);
}

TEST_CASE("bad local-light converged-tile settings are named", "[many_lights][converged][bad_input]") {
  GpuFixture fx;
  auto pass = rb::ManyLightPass::create(fx.ctx());
  RB_REQUIRE_OK(pass);
  rb::DenoiserDesc scalarDesc;
  auto scalar = rb::Denoiser::create(fx.ctx(), scalarDesc);
  RB_REQUIRE_OK(scalar);
  TestScene scene = makeRoom();
  EmbreeScene embree;
  addToEmbree(embree, scene);
  const CpuGBuffer cpu = traceGBuffer(embree, roomView(kWidth, kHeight));
  const std::vector<rb::LightSource> lights = roomLights();
  runPassFrame(
      fx, scene, cpu, false,
      [&](VkCommandBuffer cmd, const rb::GBufferDesc& desc, const rb::TlasInfo& tlas) {
        rb::ManyLightSettings s;
        s.schedule.convergedTiles.enabled = true;  // without the denoiser whose history it reads
        rb::Status st = pass.value()->record(cmd, {.gbuffer = desc, .tlas = tlas, .lights = lights, .settings = s});
        REQUIRE(!st);
        CHECK(st.error().message.find("ManyLightSettings::schedule.history is nullptr") != std::string::npos);
        s.schedule.history = scalar.value().get();  // the wrong kind of history
        st = pass.value()->record(cmd, {.gbuffer = desc, .tlas = tlas, .lights = lights, .settings = s});
        REQUIRE(!st);
        CHECK(st.error().message.find("history must be a DenoiseSignal::Rgb Denoiser") != std::string::npos);
      },
      [](const rb::GBufferDesc&) {});
  rb::HybridEffectsDesc d;
  d.effects = rb::kEffectLocalLights;
  d.localLights.schedule.convergedTiles.enabled = true;
  d.localLights.mode = rb::ManyLightMode::Exact;  // no noise, no denoiser
  auto exact = rb::HybridEffects::create(fx.ctx(), nullptr, d);
  REQUIRE(!exact);
  CHECK(exact.error().message.find("HybridEffectsDesc::localLights.schedule.convergedTiles.enabled: converged tiles "
                                   "are read from the effect's denoiser's history") != std::string::npos);
  d.localLights.mode = rb::ManyLightMode::Stochastic;
  d.localLights.disableDenoiser = true;
  auto noDenoiser = rb::HybridEffects::create(fx.ctx(), nullptr, d);
  REQUIRE(!noDenoiser);
  CHECK(noDenoiser.error().message.find("disableDenoiser = false") != std::string::npos);
}
