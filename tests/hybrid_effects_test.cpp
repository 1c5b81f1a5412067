// The effects front end and the preset table: names, the table's rows, validation of descriptions and frames
// (named errors, nothing changed on error), and the front end's output against the passes it composes.
#include <catch2/catch_test_macros.hpp>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <string>
#include <vector>

#include "synthetic_gbuffer.h"

using namespace rbtest;

TEST_CASE("preset names round-trip and the table matches the thesis", "[presets]") {
  for (uint32_t i = 0; i < rb::kPresetCount; ++i) {
    const rb::Preset p = rb::Preset(i);
    INFO(rb::toString(p));
    REQUIRE(rb::parsePreset(rb::toString(p)) == p);
    CHECK(std::string(rb::presetNames()).find(rb::toString(p)) != std::string::npos);
    const rb::PresetDesc d = rb::presetDesc(p);
    CHECK(bool(d.effects & rb::kEffectShadows) == (d.shadowRaysPerPixel > 0));
    CHECK(bool(d.effects & rb::kEffectAo) == (d.aoRaysPerPixel > 0));
    CHECK(d.aoHalfResolution == bool(d.effects & rb::kEffectAo));         // every preset with AO traces it at half res
    CHECK((d.raster.mapSize == 0) == !(d.effects & rb::kEffectShadows));  // a raster shadow map iff shadows
    // Every soft-shadow preset skips converged shadow tiles (presets.h says why); a hard shadow has none to skip.
    CHECK(d.shadowConvergedTiles == (d.shadowRaysPerPixel > 1));
  }
  CHECK(rb::parsePreset("shadows") == rb::Preset::SoftShadows);  // the old single-effect name
  CHECK_FALSE(rb::parsePreset("High").has_value());
  CHECK_FALSE(rb::parsePreset("").has_value());
  const rb::PresetDesc ultra = rb::presetDesc(rb::Preset::Ultra);
  CHECK(ultra.effects == rb::kThesisEffects);
  CHECK((ultra.shadowRaysPerPixel == 8 && ultra.aoRaysPerPixel == 16));
  CHECK((ultra.raster.mapSize == 8192 && ultra.raster.pcfKernel == 8));
  const rb::PresetDesc medium = rb::presetDesc(rb::Preset::Medium);
  CHECK(medium.effects == (rb::kEffectShadows | rb::kEffectAo));
  CHECK((medium.raster.mapSize == 4096 && medium.raster.pcfKernel == 4));
  CHECK(rb::presetDesc(rb::Preset::HardShadows).raster.mapSize == 2048);
  CHECK(rb::presetDesc(rb::Preset::Ao16).aoRaysPerPixel == 16);
  CHECK(rb::presetDesc(rb::Preset::Reflections).effects == rb::kEffectReflections);
  // withPreset keeps what the preset does not set.
  rb::HybridEffectsDesc base;
  base.ao.range = 3.0f;
  base.reflections.roughnessThreshold = 0.7f;
  const rb::HybridEffectsDesc low = rb::withPreset(base, rb::Preset::Low);
  CHECK_FALSE(low.shadows.schedule.convergedTiles.enabled);
  CHECK(rb::withPreset(base, rb::Preset::High).shadows.schedule.convergedTiles.enabled);
  CHECK(low.effects == (rb::kEffectShadows | rb::kEffectAo));
  CHECK(low.ao.schedule.halfResolution);
  CHECK(low.ao.range == 3.0f);
  CHECK(low.reflections.roughnessThreshold == 0.7f);
  CHECK(
      rb::withPreset(low, rb::Preset::HardShadows).ao.schedule.halfResolution);  // no AO in the preset: AO fields kept
  CHECK((low.shadows.raysPerPixel == 1 && low.ao.raysPerPixel == 4 && low.ao.range == 3.0f));
  CHECK(low.reflections.roughnessThreshold == 0.7f);
}

TEST_CASE("the front end rejects bad descriptions and frames by name and keeps its state",
          "[hybrid_effects][bad-input]") {
  GpuFixture fx;
  auto created = rb::HybridEffects::create(fx.ctx(), nullptr, rb::withPreset({}, rb::Preset::HardShadows));
  RB_REQUIRE_OK(created);
  rb::HybridEffects& effects = *created.value();
  const VkDeviceSize before = fx.ctx().memoryStats().total();
  struct Case {
    const char* field;
    void (*damage)(rb::HybridEffectsDesc&);
  };
  const Case cases[] = {
      {"effects", [](rb::HybridEffectsDesc& d) { d.effects = 1u << 7; }},
      {"shadows.raysPerPixel", [](rb::HybridEffectsDesc& d) { d.shadows.raysPerPixel = 5000; }},
      {"shadows.softAngularRadiusDegrees",
       [](rb::HybridEffectsDesc& d) { d.shadows.softAngularRadiusDegrees = -1.0f; }},
      {"ao.raysPerPixel", [](rb::HybridEffectsDesc& d) { d.ao.raysPerPixel = 4097; }},
      {"ao.range", [](rb::HybridEffectsDesc& d) { d.ao.range = std::numeric_limits<float>::infinity(); }},
      {"reflections.roughnessThreshold", [](rb::HybridEffectsDesc& d) { d.reflections.roughnessThreshold = 2.0f; }},
      {"reflections.raysPerPixel", [](rb::HybridEffectsDesc& d) { d.reflections.raysPerPixel = 65; }},
      {"tlasMode", [](rb::HybridEffectsDesc& d) { d.tlasMode = static_cast<rb::TlasBuildMode>(7); }},
  };
  for (const Case& c : cases) {
    INFO(c.field);
    rb::HybridEffectsDesc d = rb::withPreset({}, rb::Preset::Ultra);
    c.damage(d);
    const rb::Status s = effects.setDesc(d);
    REQUIRE_FALSE(s.ok());
    CHECK(s.error().code == rb::ErrorCode::InvalidArgument);
    CHECK(s.error().message.find(c.field) != std::string::npos);
    CHECK(effects.desc().effects == rb::kEffectShadows);  // unchanged: no AO or reflection pass was created
    CHECK(effects.aoPass() == nullptr);
    auto bad = rb::HybridEffects::create(fx.ctx(), nullptr, d);
    REQUIRE_FALSE(bad.ok());
    CHECK(bad.error().message.find(c.field) != std::string::npos);
  }
  CHECK(fx.ctx().memoryStats().total() == before);

  // A frame with neither a TLAS nor a service to build one names both ways out.
  auto cmd = fx.device().beginCommands();
  RB_REQUIRE_OK(cmd);
  rb::HybridFrame frame;
  const rb::Status s = effects.record(cmd.value(), frame);
  REQUIRE_FALSE(s.ok());
  CHECK(s.error().message.find("HybridFrame::tlas") != std::string::npos);
  CHECK(s.error().message.find("AccelerationStructureService") != std::string::npos);
  CHECK(effects.outputs().shadow.width == 1);  // still the neutral image: no frame was recorded
  RB_REQUIRE_OK(fx.device().submitAndWait(cmd.value()));
}

TEST_CASE("the front end's hard shadows and AO equal the passes recorded one by one", "[hybrid_effects]") {
  GpuFixture fx;
  TestScene scene = makeConformanceScene();
  EmbreeScene embree;
  addToEmbree(embree, scene);
  CpuGBuffer cpu = traceGBuffer(embree, conformanceView(64, 48));
  auto service = rb::AccelerationStructureService::create(fx.ctx());
  RB_REQUIRE_OK(service);
  BuiltScene built = buildScene(fx, *service.value(), scene);
  GpuGBuffer gbuffer(fx, cpu);

  rb::HybridEffectsDesc desc = rb::withPreset({}, rb::Preset::Low);  // hard shadows, AO 4 rays
  desc.ao.disableDenoiser = true;                                    // compare the raw AO
  desc.ao.schedule.halfResolution = false;                           // as the AO pass below, which traces every pixel
  desc.ao.range = 2.0f;
  auto effects = rb::HybridEffects::create(fx.ctx(), service.value().get(), desc);
  RB_REQUIRE_OK(effects);
  auto shadowPass = rb::ShadowPass::create(fx.ctx());
  RB_REQUIRE_OK(shadowPass);
  auto aoPass = rb::AoPass::create(fx.ctx());
  RB_REQUIRE_OK(aoPass);

  rb::HybridFrame frame;
  frame.gbuffer = gbuffer.desc();
  frame.tlas = &built.tlas;  // the engine's own TLAS: the front end builds none
  frame.light.direction[0] = 0.4f;
  frame.light.direction[1] = 1.0f;
  frame.light.direction[2] = 0.3f;
  frame.light.angularRadiusDegrees = 3.0f;  // ignored: one ray per pixel is hard shadows
  auto cmd = fx.device().beginCommands();
  RB_REQUIRE_OK(cmd);
  fx.ctx().beginFrame();
  RB_REQUIRE_OK(effects.value()->record(cmd.value(), frame));
  rb::Light hard = frame.light;
  hard.angularRadiusDegrees = 0.0f;
  RB_REQUIRE_OK(shadowPass.value()->record(cmd.value(), {.gbuffer = frame.gbuffer, .tlas = built.tlas, .light = hard}));
  rb::AoSettings ao;
  ao.raysPerPixel = 4;
  ao.range = 2.0f;
  RB_REQUIRE_OK(aoPass.value()->record(cmd.value(), {.gbuffer = frame.gbuffer, .tlas = built.tlas, .settings = ao}));
  RB_REQUIRE_OK(fx.device().submitAndWait(cmd.value()));

  const rb::HybridOutputs& out = effects.value()->outputs();
  CHECK(out.shadow.view == out.shadowRaw.view);  // hard shadows: no denoiser
  CHECK(effects.value()->shadowDenoiser() == nullptr);
  CHECK(out.reflection.width == 1);  // off: the neutral image
  CHECK(effects.value()->lastTlas().tlas == built.tlas.tlas);
  const std::vector<float> frontShadow = readR16f(fx, out.shadow.image, 64, 48);
  const std::vector<float> passShadow = readR16f(fx, shadowPass.value()->outputs().visibility, 64, 48);
  const std::vector<float> frontAo = readR16f(fx, out.ao.image, 64, 48);
  const std::vector<float> passAo = readR16f(fx, aoPass.value()->outputs().ao, 64, 48);
  CHECK(frontShadow == passShadow);  // same rays, same seeds (frame index): bit-identical
  CHECK(frontAo == passAo);
  uint32_t shadowed = 0;
  for (float v : frontShadow) shadowed += v < 0.5f;
  CHECK(shadowed > 0);  // the conformance scene casts shadows: the comparison is not of two empty images

  effects.value().reset();
  shadowPass.value().reset();
  aoPass.value().reset();
  destroyScene(fx, built);
}

TEST_CASE("the front end denoises glossy reflections, keeps coverage, and can be told not to", "[hybrid_effects]") {
  GpuFixture fx;
  TestScene scene = makeConformanceScene();
  EmbreeScene embree;
  addToEmbree(embree, scene);
  const uint32_t w = 64, h = 48;
  // Glossy everywhere but the rotated box (instance 4), a mirror; the threshold leaves the spheres untraced.
  std::vector<float> roughness(scene.instances.size(), 0.4f);
  roughness[1] = roughness[2] = 0.9f;
  roughness[4] = 0.0f;
  CpuGBuffer cpu = traceGBuffer(embree, conformanceView(w, h), roughness);
  auto service = rb::AccelerationStructureService::create(fx.ctx());
  RB_REQUIRE_OK(service);
  BuiltScene built = buildScene(fx, *service.value(), scene);
  GpuGBuffer gbuffer(fx, cpu);

  rb::HybridEffectsDesc desc;
  desc.effects = rb::kEffectReflections;
  desc.reflections.roughnessThreshold = 0.5f;
  auto effects = rb::HybridEffects::create(fx.ctx(), service.value().get(), desc);
  RB_REQUIRE_OK(effects);
  rb::HybridEffects& fxs = *effects.value();
  auto frame = [&] {
    fx.runFrame([&](VkCommandBuffer cmd) {
      rb::HybridFrame f;
      f.gbuffer = gbuffer.desc();
      f.instances = built.instances;
      RB_REQUIRE_OK(fxs.record(cmd, f));
    });
  };
  auto rgbRmse = [&](const std::vector<float>& a, const std::vector<float>& b) {
    double sum = 0.0;
    size_t count = 0;
    for (size_t i = 0; i < size_t(w) * h; ++i) {
      if (b[i * 4 + 3] < 0.5f) continue;
      for (int k = 0; k < 3; ++k) sum += (double(a[i * 4 + k]) - b[i * 4 + k]) * (double(a[i * 4 + k]) - b[i * 4 + k]);
      count += 3;
    }
    return std::sqrt(sum / double(count));
  };

  // The reference: raw, 64 rays per frame, averaged over 8 frames.
  desc.reflections.raysPerPixel = 64;
  desc.reflections.disableDenoiser = true;
  RB_REQUIRE_OK(fxs.setDesc(desc));
  std::vector<float> reference(size_t(w) * h * 4, 0.0f);
  for (int i = 0; i < 8; ++i) {
    frame();
    std::vector<float> img = readRgba16f(fx, fxs.outputs().reflection.image, w, h);
    for (size_t k = 0; k < img.size(); ++k) reference[k] += img[k] / 8.0f;
  }

  desc.reflections.raysPerPixel = 2;
  desc.reflections.disableDenoiser = false;  // the default
  RB_REQUIRE_OK(fxs.setDesc(desc));
  frame();
  REQUIRE(fxs.reflectionDenoiser() != nullptr);
  CHECK(fxs.reflectionDenoiser()->signal() == rb::DenoiseSignal::Reflection);
  const rb::HybridOutputs& out = fxs.outputs();
  REQUIRE(out.reflection.image != VK_NULL_HANDLE);
  CHECK(out.reflection.image != out.reflectionRaw.image);
  CHECK(out.reflection.image == fxs.reflectionDenoiser()->outputs().denoised);
  CHECK(out.reflectionRaw.image == fxs.reflectionPass()->outputs().radiance);
  CHECK(out.reflection.format == VK_FORMAT_R16G16B16A16_SFLOAT);
  const std::vector<float> raw = readRgba16f(fx, out.reflectionRaw.image, w, h);
  const std::vector<float> denoised = readRgba16f(fx, out.reflection.image, w, h);
  size_t covered = 0;
  for (size_t i = 0; i < size_t(w) * h; ++i) {
    for (int k = 0; k < 4; ++k) REQUIRE(std::isfinite(denoised[i * 4 + k]));
    REQUIRE(denoised[i * 4 + 3] == raw[i * 4 + 3]);  // coverage is the pass's, untouched
    covered += raw[i * 4 + 3] > 0.5f;
  }
  CHECK(covered > size_t(w) * h / 4);
  CHECK(covered < size_t(w) * h);  // the spheres (roughness 0.9) trace nothing: coverage 0 must survive
  const double eRaw = rgbRmse(raw, reference), eDenoised = rgbRmse(denoised, reference);
  std::printf("[hybrid_effects] reflections, 2 rays, one frame, 64x48: RMSE raw %.4f, denoised %.4f\n", eRaw,
              eDenoised);
  INFO("RMSE raw " << eRaw << ", denoised " << eDenoised);
  CHECK(eDenoised < eRaw);
  for (uint32_t i = 0; i < fx.ctx().framesInFlight(); ++i) fx.ctx().beginFrame();
  (void)fx.device().waitIdle();
  const rb::HybridStats stats = fxs.stats();
  CHECK(stats.reflectionDenoise.gpuMs > 0.0);
  CHECK(stats.reflectionDenoise.rays == 0);
  CHECK(stats.totalGpuMs() >= stats.reflection.gpuMs + stats.reflectionDenoise.gpuMs);

  // disableDenoiser: the raw image, no denoiser.
  desc.reflections.disableDenoiser = true;
  RB_REQUIRE_OK(fxs.setDesc(desc));
  frame();
  CHECK(fxs.reflectionDenoiser() == nullptr);
  CHECK(fxs.outputs().reflection.image == fxs.outputs().reflectionRaw.image);
  for (uint32_t i = 0; i < fx.ctx().framesInFlight(); ++i) fx.ctx().beginFrame();
  (void)fx.device().waitIdle();
  effects.value().reset();
  destroyScene(fx, built);
}
