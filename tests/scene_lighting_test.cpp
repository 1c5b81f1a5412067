// rb::SceneLighting: sun, sky and ambient described once and resolved by one function (sdk/src/trace/
// scene_lighting_resolve.h) for reflection hits, the pure ray-traced mode and the front end: the same zeros mean the
// same defaults, explicitValues keeps them, and a bad value is refused with the same message by every effect.
#include <catch2/catch_test_macros.hpp>

#include <cmath>
#include <string>

#include "scene_lighting_resolve.h"
#include "synthetic_gbuffer.h"

using namespace rbtest;

TEST_CASE("SceneLighting resolves zeros to the named defaults unless explicitValues", "[scene_lighting]") {
  rb::SceneLighting zero;
  auto d = rb::resolveSceneLighting(zero, "L");
  RB_REQUIRE_OK(d);
  CHECK((d->sunDirection[0] == 0.0f && d->sunDirection[1] == 1.0f && d->sunDirection[2] == 0.0f));
  for (int i = 0; i < 3; ++i) {
    CHECK(d->sunRadiance[i] == rb::kDefaultSunRadiance);
    CHECK(d->skyRadiance[i] == rb::kDefaultSkyRadiance[i]);
  }
  CHECK(d->ambientIntensity == rb::kDefaultAmbientIntensity);

  rb::SceneLighting black;
  black.explicitValues = true;
  auto b = rb::resolveSceneLighting(black, "L");
  RB_REQUIRE_OK(b);
  for (int i = 0; i < 3; ++i) CHECK((b->sunRadiance[i] == 0.0f && b->skyRadiance[i] == 0.0f));
  CHECK(b->ambientIntensity == 0.0f);

  rb::SceneLighting moon;
  moon.noSun = true;
  moon.sunRadiance[0] = 5.0f;
  moon.sunDirection[0] = 3.0f, moon.sunDirection[2] = 4.0f;
  auto m = rb::resolveSceneLighting(moon, "L");
  RB_REQUIRE_OK(m);
  for (int i = 0; i < 3; ++i) {
    CHECK(m->sunRadiance[i] == 0.0f);  // no sun, whatever its radiance says
    CHECK(m->skyRadiance[i] == rb::kDefaultSkyRadiance[i]);
  }
  CHECK(std::fabs(m->sunDirection[0] - 0.6f) < 1e-6f);
  CHECK(std::fabs(m->sunDirection[2] - 0.8f) < 1e-6f);
}

TEST_CASE("reflections, primary shading and the front end refuse the same bad SceneLighting by the same name",
          "[scene_lighting][bad_input][reflection][primary-shading][hybrid_effects]") {
  GpuFixture fx;
  TestScene scene = makeConformanceScene();
  EmbreeScene embree;
  addToEmbree(embree, scene);
  CpuGBuffer cpu = traceGBuffer(embree, conformanceView(32, 24), {0.2f, 0.2f, 0.2f, 0.2f, 0.2f, 0.2f});
  auto service = rb::AccelerationStructureService::create(fx.ctx());
  RB_REQUIRE_OK(service);
  rb::TlasBuildOptions options;
  options.writeShadingRecords = true;
  BuiltScene built = buildScene(fx, *service.value(), scene, options);
  GpuGBuffer gbuffer(fx, cpu);
  auto reflection = rb::ReflectionPass::create(fx.ctx());
  auto shading = rb::PrimaryShadingPass::create(fx.ctx());
  auto effects = rb::HybridEffects::create(fx.ctx(), service.value().get(), {.effects = rb::kEffectReflections});
  RB_REQUIRE_OK(reflection);
  RB_REQUIRE_OK(shading);
  RB_REQUIRE_OK(effects);
  struct Case {
    const char* message;
    void (*damage)(rb::SceneLighting&);
  };
  const Case cases[] = {
      {"lighting.sunDirection must be finite", [](rb::SceneLighting& l) { l.sunDirection[1] = NAN; }},
      {"lighting.sunRadiance must be finite and >= 0", [](rb::SceneLighting& l) { l.sunRadiance[2] = INFINITY; }},
      {"lighting.skyRadiance must be finite and >= 0", [](rb::SceneLighting& l) { l.skyRadiance[0] = -1.0f; }},
      {"lighting.ambientIntensity -0.500000 must be finite and >= 0",
       [](rb::SceneLighting& l) { l.ambientIntensity = -0.5f; }},
  };
  const rb::PrimaryRayCamera camera = conformanceCamera();
  fx.runFrame([&](VkCommandBuffer cmd) {
    for (const Case& c : cases) {
      INFO(c.message);
      rb::ReflectionSettings r;
      c.damage(r.lighting);
      const rb::Status reflected =
          reflection.value()->record(cmd, {.gbuffer = gbuffer.desc(), .tlas = built.tlas, .settings = r});
      rb::PrimaryShadingSettings p;
      c.damage(p.lighting);
      const rb::Status shaded =
          shading.value()->record(cmd, {.tlas = built.tlas, .camera = camera, .targets = {8, 8}, .settings = p});
      rb::HybridFrame frame;
      frame.gbuffer = gbuffer.desc();
      frame.tlas = &built.tlas;
      c.damage(frame.lighting);
      const bool directionCase = std::string(c.message).find("sunDirection") != std::string::npos;
      for (const rb::Status* st : {&reflected, &shaded}) {
        INFO(st->what());
        REQUIRE_FALSE(st->ok());
        CHECK(st->error().code == rb::ErrorCode::InvalidArgument);
        CHECK(std::string(st->what()).find(c.message) != std::string::npos);
      }
      CHECK(std::string(reflected.what()).rfind("ReflectionPass: ReflectionSettings::lighting.", 0) == 0);
      CHECK(std::string(shaded.what()).rfind("PrimaryShadingPass: PrimaryShadingSettings::lighting.", 0) == 0);
      if (!directionCase) {
        const rb::Status front = effects.value()->record(cmd, frame);
        INFO(front.what());
        REQUIRE_FALSE(front.ok());
        CHECK(std::string(front.what()).find(c.message) != std::string::npos);
      }
    }
  });
  reflection.value().reset();
  shading.value().reset();
  effects.value().reset();
  destroyScene(fx, built);
}
