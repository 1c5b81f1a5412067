// Tests of the sample-engine adapter itself: raster vs hybrid shadows on the demo scene, pass memory that follows
// the enabled effects. The validation layer is on; any error fails. The programs built on the adapter are tested
// in tools/tests.
#include <memory>

#include <catch2/catch_test_macros.hpp>

#include "raybridge_sample_engine_adapter.h"
#include "sample_engine/procedural.h"

namespace se = sample_engine;

namespace {

// An engine set up by the adapter, with the validation layer on.
std::unique_ptr<se::Engine> makeEngine() {
  rb::RequiredFeatures features;
  se::EngineConfig config;
  config.enableValidation = true;
  rbAdapter::configureEngine(config, features);
  auto engine = se::Engine::create(config);
  INFO(engine.error);
  REQUIRE(engine.ok());
  return std::move(engine.value);
}

}  // namespace

TEST_CASE("hybrid and raster shadow the same ground regions of the demo scene", "[adapter][shadows]") {
  auto engine = makeEngine();
  REQUIRE(engine->loadScene(se::makeDefaultDemoScene()).ok());
  const uint32_t w = 256, h = 144;
  REQUIRE(engine->setRenderSize(w, h).ok());
  auto adapter = rbAdapter::Adapter::create(*engine, {.preset = rb::Preset::HardShadows});
  INFO(adapter.error);
  REQUIRE(adapter.ok());
  engine->setPrepassHook(adapter.value->prepassHook());

  se::FrameParams params;
  params.camera = *engine->scene().camera;
  params.sun = *engine->scene().sun;
  auto render = [&](int frames) {
    for (int i = 0; i < frames; ++i) REQUIRE(engine->renderFrame(params).ok());
    auto hdr = engine->readbackHdr();
    REQUIRE(hdr.ok());
    return hdr.value;
  };
  const se::ImageRGBA32F hybrid = render(2);
  adapter.value->settings().enabled = false;  // the engine's shadow map
  const se::ImageRGBA32F raster = render(1);
  params.sun.intensity = 0.0f;  // ambient and emissive only: what a fully shadowed pixel receives
  const se::ImageRGBA32F ambient = render(1);
  CHECK(adapter.value->lastError().empty());

  // Lighting is linear in sun visibility, so a pixel is in shadow when the sun adds (almost) nothing to it.
  // Ground: the lower half of the image, minus sky-coloured pixels.
  auto luminance = [](glm::vec4 c) { return 0.2126f * c.r + 0.7152f * c.g + 0.0722f * c.b; };
  uint32_t both = 0, either = 0, hybridOnly = 0, rasterOnly = 0, ground = 0;
  for (uint32_t y = h / 2; y < h; ++y) {
    for (uint32_t x = 0; x < w; ++x) {
      const float base = luminance(ambient.at(x, y));
      if (glm::length(glm::vec3(ambient.at(x, y)) - params.skyColor) < 1e-3f) continue;
      ++ground;
      const bool hs = luminance(hybrid.at(x, y)) - base < 0.3f * base;
      const bool rs = luminance(raster.at(x, y)) - base < 0.3f * base;
      both += hs && rs;
      either += hs || rs;
      hybridOnly += hs && !rs;
      rasterOnly += rs && !hs;
    }
  }
  INFO("ground " << ground << " shadowed in both " << both << ", hybrid only " << hybridOnly << ", raster only "
                 << rasterOnly);
  CHECK(both > ground / 50);                   // there are shadows on the ground in both modes
  CHECK(double(both) / double(either) > 0.7);  // and they overlap substantially
  engine->setPrepassHook({});
  adapter.value.reset();
  CHECK(engine->validationErrorCount() == 0);
}

namespace {

// The two 1x1 neutral images a HybridEffects names for the effects that are off (hybrid_effects.h, "Outputs"),
// measured on `ctx` with a probe (retired at once; measure the adapter before calling this).
VkDeviceSize neutralImageBytes(rb::Context& ctx) {
  const VkDeviceSize before = ctx.memoryStats().of(rb::MemoryCategory::PassImages);
  auto probe = rb::HybridEffects::create(ctx, nullptr, {});
  REQUIRE(probe.ok());
  const VkDeviceSize bytes = ctx.memoryStats().of(rb::MemoryCategory::PassImages) - before;
  CHECK(bytes > 0);
  CHECK(bytes <= 2 * 65536);  // two 1x1 images, whatever the driver's alignment
  return bytes;
}

}  // namespace

TEST_CASE("the adapter without effects allocates only the neutral outputs and builds nothing", "[adapter][memory]") {
  auto engine = makeEngine();
  REQUIRE(engine->loadScene(se::makeDefaultDemoScene()).ok());
  REQUIRE(engine->setRenderSize(64, 48).ok());
  auto adapter = rbAdapter::Adapter::create(*engine, {});  // zero config: no effect
  INFO(adapter.error);
  REQUIRE(adapter.ok());
  CHECK(adapter.value->effects().shadowPass() == nullptr);
  engine->setPrepassHook(adapter.value->prepassHook());
  se::FrameParams params;
  params.camera = *engine->scene().camera;
  for (int i = 0; i < 3; ++i) REQUIRE(engine->renderFrame(params).ok());
  REQUIRE(engine->waitIdle().ok());
  const rb::MemoryStats memory = adapter.value->context().memoryStats();
  CHECK(memory.of(rb::MemoryCategory::PassImages) == neutralImageBytes(adapter.value->context()));
  CHECK(memory.of(rb::MemoryCategory::BlasStorage) == 0);
  CHECK(adapter.value->context().frameIndex() == 3);  // frames are still paced
  CHECK(adapter.value->lastError().empty());
  engine->setPrepassHook({});
  adapter.value.reset();
  CHECK(engine->validationErrorCount() == 0);
}

TEST_CASE("the adapter with shadows allocates the visibility image once frames are recorded", "[adapter][memory]") {
  auto engine = makeEngine();
  REQUIRE(engine->loadScene(se::makeDefaultDemoScene()).ok());
  REQUIRE(engine->setRenderSize(64, 48).ok());
  auto adapter = rbAdapter::Adapter::create(*engine, {.preset = rb::Preset::HardShadows});
  REQUIRE(adapter.ok());
  engine->setPrepassHook(adapter.value->prepassHook());
  se::FrameParams params;
  params.camera = *engine->scene().camera;
  REQUIRE(engine->renderFrame(params).ok());
  REQUIRE(engine->waitIdle().ok());
  CHECK(adapter.value->context().memoryStats().of(rb::MemoryCategory::PassImages) >= 64 * 48 * 2);
  CHECK(adapter.value->effects().lastTlas().instanceCount == engine->scene().instances.size());
  engine->setPrepassHook({});
  adapter.value.reset();
  CHECK(engine->validationErrorCount() == 0);
}

TEST_CASE("pass memory follows the enabled effects at run time", "[adapter][memory][effects]") {
  auto engine = makeEngine();
  REQUIRE(engine->loadScene(se::makeDefaultDemoScene()).ok());
  REQUIRE(engine->setRenderSize(64, 48).ok());
  auto created = rbAdapter::Adapter::create(*engine, {.preset = rb::Preset::HardShadows});
  INFO(created.error);
  REQUIRE(created.ok());
  rbAdapter::Adapter& adapter = *created.value;
  rb::HybridEffects& fx = adapter.effects();
  engine->setPrepassHook(adapter.prepassHook());
  se::FrameParams params;
  params.camera = *engine->scene().camera;
  params.sun = *engine->scene().sun;
  auto settle = [&] {  // frames in flight retire what was disabled; then release it while idle
    for (uint32_t i = 0; i < se::kFramesInFlight + 1; ++i) REQUIRE(engine->renderFrame(params).ok());
    REQUIRE(engine->waitIdle().ok());
    adapter.context().releaseAfterIdle();
    INFO(adapter.lastError());
    REQUIRE(adapter.lastError().empty());
    return adapter.context().memoryStats();
  };
  using C = rb::MemoryCategory;
  const rb::MemoryStats shadowOnly = settle();
  CHECK(shadowOnly.of(C::PassImages) >= 64 * 48 * 2);
  CHECK(shadowOnly.of(C::PassBuffers) > 0);
  CHECK(fx.aoPass() == nullptr);
  CHECK(fx.reflectionPass() == nullptr);
  CHECK(fx.shadowDenoiser() == nullptr);  // hard shadows are never denoised

  REQUIRE(fx.applyPreset(rb::Preset::Ultra).ok());  // the thesis's three effects, soft shadows: two denoisers
  const rb::MemoryStats all = settle();
  CHECK(fx.desc().effects == rb::kThesisEffects);
  CHECK(fx.aoPass() != nullptr);
  CHECK(fx.reflectionPass() != nullptr);
  CHECK(fx.shadowDenoiser() != nullptr);
  CHECK(fx.aoDenoiser() != nullptr);
  // AO image + reflection image + two denoisers' history: well above the shadow-only images.
  CHECK(all.of(C::PassImages) >= shadowOnly.of(C::PassImages) + 64 * 48 * (2 + 8));
  CHECK(all.of(C::PassBuffers) > shadowOnly.of(C::PassBuffers));
  const rb::HybridStats stats = fx.stats();
  CHECK(stats.ao.rays > 0);
  CHECK(stats.reflection.rays > 0);
  // Ultra: 8 soft shadow rays per lit pixel, 16 AO rays per surface pixel of one in each 2x2 block (AO at half
  // resolution), at most.
  CHECK(fx.desc().ao.schedule.halfResolution);
  CHECK(stats.shadow.rays <= uint64_t(64 * 48 * 8));
  CHECK(stats.ao.rays <= uint64_t(32 * 24 * 16));
  CHECK(stats.ao.rays > uint64_t(32 * 24 * 4));

  rb::HybridEffectsDesc raw = fx.desc();  // the denoisers go, the passes stay
  raw.shadows.disableDenoiser = raw.ao.disableDenoiser = true;
  // Ultra's converged shadow tiles read the shadow denoiser's history: refused by name while they are on.
  const rb::Status refused = fx.setDesc(raw);
  REQUIRE_FALSE(refused.ok());
  CHECK(refused.error().message.find("shadows.schedule.convergedTiles.enabled") != std::string::npos);
  raw.shadows.schedule.convergedTiles.enabled = false;
  REQUIRE(fx.setDesc(raw).ok());
  const rb::MemoryStats rawMemory = settle();
  CHECK(fx.shadowDenoiser() == nullptr);
  CHECK(fx.aoDenoiser() == nullptr);
  CHECK(rawMemory.of(C::PassImages) < all.of(C::PassImages));

  REQUIRE(fx.applyPreset(rb::Preset::HardShadows).ok());
  const rb::MemoryStats back = settle();
  CHECK(fx.aoPass() == nullptr);
  CHECK(fx.reflectionPass() == nullptr);
  CHECK(back.of(C::PassImages) == shadowOnly.of(C::PassImages));
  CHECK(back.of(C::PassBuffers) == shadowOnly.of(C::PassBuffers));

  REQUIRE(fx.applyPreset(rb::Preset::None).ok());
  const rb::MemoryStats none = settle();
  CHECK(fx.shadowPass() == nullptr);
  CHECK(none.of(C::PassImages) == neutralImageBytes(adapter.context()));  // what the outputs name now
  CHECK(none.of(C::PassBuffers) == 0);

  engine->setPrepassHook({});
  created.value.reset();
  CHECK(engine->validationErrorCount() == 0);
}
