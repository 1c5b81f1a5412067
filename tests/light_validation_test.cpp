// One rb::Light validator (sdk/src/trace/light_validation.h): every effect that takes a light refuses the same bad
// light with the same message naming the field, before anything is recorded. The shadow pass once accepted a non-finite
// point-light position that the many-light pass refused.
#include <catch2/catch_test_macros.hpp>

#include <cmath>
#include <string>
#include <vector>

#include "many_light_scene.h"
#include "synthetic_gbuffer.h"

using namespace rbtest;

TEST_CASE("every effect that takes a light refuses the same bad light with the same message",
          "[bad_input][lights][shadow][many_lights][hybrid_effects]") {
  GpuFixture fx;
  TestScene scene = makeRoom();
  EmbreeScene embree;
  addToEmbree(embree, scene);
  CpuGBuffer cpu = traceGBuffer(embree, roomView(32, 24));
  auto service = rb::AccelerationStructureService::create(fx.ctx());
  RB_REQUIRE_OK(service);
  BuiltScene built = buildScene(fx, *service.value(), scene);
  GpuGBuffer gbuffer(fx, cpu);
  auto shadowPass = rb::ShadowPass::create(fx.ctx());
  RB_REQUIRE_OK(shadowPass);
  auto manyLights = rb::ManyLightPass::create(fx.ctx());
  RB_REQUIRE_OK(manyLights);
  auto lightList = rb::LightList::create(fx.ctx());
  RB_REQUIRE_OK(lightList);
  auto effects = rb::HybridEffects::create(fx.ctx(), service.value().get(),
                                           {.effects = rb::kEffectShadows | rb::kEffectLocalLights});
  RB_REQUIRE_OK(effects);

  struct Case {
    const char* field;
    void (*damage)(rb::Light&);
  };
  const Case cases[] = {
      {"Light::position must be finite",
       [](rb::Light& l) { l.type = rb::LightType::Point, l.position[1] = std::nan(""); }},
      {"Light::position must be finite", [](rb::Light& l) { l.type = rb::LightType::Spot, l.position[0] = INFINITY; }},
      {"Light::direction must be a finite vector", [](rb::Light& l) { l.direction[2] = NAN; }},
      {"Light::angularRadiusDegrees 50.000000 is outside [0, 45)", [](rb::Light& l) { l.angularRadiusDegrees = 50; }},
      {"Light::radius must be finite and >= 0", [](rb::Light& l) { l.type = rb::LightType::Point, l.radius = -1; }},
      {"Light::range must be finite and >= 0", [](rb::Light& l) { l.type = rb::LightType::Spot, l.range = INFINITY; }},
      {"Light::spotOuterAngleDegrees 120.000000 is outside (0, 90]",
       [](rb::Light& l) { l.type = rb::LightType::Spot, l.spotOuterAngleDegrees = 120; }},
      {"Light::type has an unknown value", [](rb::Light& l) { l.type = rb::LightType(9); }},
  };
  fx.runFrame([&](VkCommandBuffer cmd) {
    for (const Case& c : cases) {
      INFO(c.field);
      rb::Light light;
      light.position[0] = 1.0;
      light.position[1] = 2.0;
      c.damage(light);
      const rb::Status shadow =
          shadowPass.value()->record(cmd, {.gbuffer = gbuffer.desc(), .tlas = built.tlas, .light = light});
      std::vector<rb::LightSource> list(1);
      list[0].light = light;
      const rb::Status many =
          manyLights.value()->record(cmd, {.gbuffer = gbuffer.desc(), .tlas = built.tlas, .lights = list});
      const rb::Status shared = lightList.value()->record(cmd, built.tlas, list);
      rb::HybridFrame frame;
      frame.gbuffer = gbuffer.desc();
      frame.instances = built.instances;
      frame.light = light;
      const rb::Status front = effects.value()->record(cmd, frame);
      for (const rb::Status* st : {&shadow, &many, &shared, &front}) {
        INFO(st->what());
        REQUIRE_FALSE(st->ok());
        CHECK(st->error().code == rb::ErrorCode::InvalidArgument);
        CHECK(std::string(st->what()).find(c.field) != std::string::npos);
      }
      CHECK(std::string(shadow.what()).rfind("ShadowPass: ", 0) == 0);
      CHECK(std::string(many.what()).find("lights[0]: ") != std::string::npos);
      CHECK(std::string(shared.what()).rfind("LightList::record: lights[0]: ", 0) == 0);
      CHECK(std::string(front.what()).find("HybridFrame::light: ") != std::string::npos);
    }
  });
  // A good point light passes all three (and the command buffer they recorded into is valid).
  fx.runFrame([&](VkCommandBuffer cmd) {
    rb::Light point;
    point.type = rb::LightType::Point;
    point.position[1] = 2.0;
    RB_REQUIRE_OK(shadowPass.value()->record(cmd, {.gbuffer = gbuffer.desc(), .tlas = built.tlas, .light = point}));
  });
  shadowPass.value().reset();
  manyLights.value().reset();
  lightList.value().reset();
  effects.value().reset();
  destroyScene(fx, built);
}
