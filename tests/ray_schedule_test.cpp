// One RaySchedule validator (sdk/src/schedule/ray_schedule_stage.h) for every effect: each pass and the HybridEffects
// front end refuse a stage the effect does not have, and a bad member of a stage it has, with one message that names
// the field once (the pass's settings, or HybridEffectsDesc's effect), before anything is recorded.
#include <raybridge/ray_schedule.h>

#include <catch2/catch_test_macros.hpp>

#include <functional>
#include <string>
#include <vector>

#include "many_light_scene.h"
#include "synthetic_gbuffer.h"

using namespace rbtest;

namespace {

size_t occurrences(const std::string& text, const std::string& needle) {
  size_t n = 0;
  for (size_t at = text.find(needle); at != std::string::npos; at = text.find(needle, at + 1)) ++n;
  return n;
}

// A stage outside `allowed` and one bad member of an allowed stage, per effect.
struct Damage {
  const char* member;  // what the message must name after "<field>."
  void (*apply)(rb::RaySchedule&);
};

std::vector<Damage> damagesFor(uint32_t allowed) {
  std::vector<Damage> d;
  if (!(allowed & rb::kScheduleAdaptiveRays))
    d.push_back(
        {"adaptive.enabled: this effect has no adaptive rays", [](rb::RaySchedule& s) { s.adaptive.enabled = true; }});
  if (!(allowed & rb::kScheduleHalfResolution))
    d.push_back(
        {"halfResolution: this effect has no half resolution", [](rb::RaySchedule& s) { s.halfResolution = true; }});
  if (!(allowed & rb::kScheduleTileClassifier))
    d.push_back(
        {"tileClassifier: this effect has no tile classifier", [](rb::RaySchedule& s) { s.tileClassifier = true; }});
  if (!(allowed & rb::kScheduleResetRays))
    d.push_back({"resetRays: this effect has no reset rays (ray_schedule.h lists each effect's stages); set it to 0",
                 [](rb::RaySchedule& s) { s.resetRays = 8; }});
  if (allowed & rb::kScheduleResetRays)
    d.push_back({"resetRays 5000 exceeds kMaxRaysPerPixel (4096)", [](rb::RaySchedule& s) { s.resetRays = 5000; }});
  if (allowed & rb::kScheduleResetRays && allowed & rb::kScheduleAdaptiveRays)
    d.push_back(
        {"resetRays: adaptive rays already plan the most rays where a history restarts", [](rb::RaySchedule& s) {
           s.resetRays = 8;
           s.adaptive.enabled = true;
         }});
  if (allowed & rb::kScheduleResetRays && allowed & rb::kScheduleHalfResolution)
    d.push_back({"resetRays traces more rays in the changed full-resolution pixels: set it to 0 or disable "
                 "halfResolution",
                 [](rb::RaySchedule& s) {
                   s.resetRays = 8;
                   s.halfResolution = true;
                 }});
  if (allowed & rb::kScheduleAdaptiveRays)
    d.push_back({"adaptive.tileWidth 3 must be 0", [](rb::RaySchedule& s) {
                   s.adaptive.enabled = true;
                   s.adaptive.tileWidth = 3;
                 }});
  d.push_back({"convergedTiles.maxNoise", [](rb::RaySchedule& s) {
                 s.convergedTiles.enabled = true;
                 s.convergedTiles.maxNoise = -1.0f;
               }});
  if (allowed & rb::kScheduleHalfResolution)
    d.push_back({"convergedTiles skips tiles of full-resolution pixels", [](rb::RaySchedule& s) {
                   s.convergedTiles.enabled = true;
                   s.halfResolution = true;
                 }});
  return d;
}

}  // namespace

TEST_CASE("every effect's RaySchedule is checked by one validator that names the bad field once",
          "[bad_input][schedule][shadow][ao][reflection][many_lights][hybrid_effects]") {
  GpuFixture fx;
  TestScene scene = makeRoom();
  EmbreeScene embree;
  addToEmbree(embree, scene);
  CpuGBuffer cpu = traceGBuffer(embree, roomView(32, 24));
  auto service = rb::AccelerationStructureService::create(fx.ctx());
  RB_REQUIRE_OK(service);
  BuiltScene built = buildScene(fx, *service.value(), scene);
  GpuGBuffer gbuffer(fx, cpu);
  auto shadow = rb::ShadowPass::create(fx.ctx());
  auto ao = rb::AoPass::create(fx.ctx());
  auto reflection = rb::ReflectionPass::create(fx.ctx());
  auto lights = rb::ManyLightPass::create(fx.ctx());
  RB_REQUIRE_OK(shadow);
  RB_REQUIRE_OK(ao);
  RB_REQUIRE_OK(reflection);
  RB_REQUIRE_OK(lights);
  auto scalar = rb::Denoiser::create(fx.ctx());
  auto reflected = rb::Denoiser::create(fx.ctx(), rb::DenoiserDesc{rb::DenoiseSignal::Reflection});
  auto rgb = rb::Denoiser::create(fx.ctx(), rb::DenoiserDesc{rb::DenoiseSignal::Rgb});
  RB_REQUIRE_OK(scalar);
  RB_REQUIRE_OK(reflected);
  RB_REQUIRE_OK(rgb);
  std::vector<rb::LightSource> list(1);
  list[0].light.type = rb::LightType::Point;

  struct Effect {
    const char* field;          // the pass's name for the schedule
    const char* frontEndField;  // HybridEffectsDesc's
    uint32_t allowed;
    const rb::Denoiser* history;
    std::function<rb::Status(VkCommandBuffer, const rb::RaySchedule&)> record;
    std::function<void(rb::HybridEffectsDesc&, const rb::RaySchedule&)> describe;
  };
  rb::Light soft;
  soft.angularRadiusDegrees = 2.0f;
  const Effect effects[] = {
      {"ShadowPass: ShadowSettings::schedule", "HybridEffectsDesc::shadows.schedule", rb::kShadowScheduleCapabilities,
       scalar.value().get(),
       [&](VkCommandBuffer cmd, const rb::RaySchedule& s) {
         rb::ShadowSettings settings;
         settings.schedule = s;
         return shadow.value()->record(
             cmd, {.gbuffer = gbuffer.desc(), .tlas = built.tlas, .light = soft, .settings = settings});
       },
       [](rb::HybridEffectsDesc& d, const rb::RaySchedule& s) {
         d.effects = rb::kEffectShadows;
         d.shadows.schedule = s;
       }},
      {"AoPass: AoSettings::schedule", "HybridEffectsDesc::ao.schedule", rb::kAoScheduleCapabilities,
       scalar.value().get(),
       [&](VkCommandBuffer cmd, const rb::RaySchedule& s) {
         rb::AoSettings settings;
         settings.schedule = s;
         return ao.value()->record(cmd, {.gbuffer = gbuffer.desc(), .tlas = built.tlas, .settings = settings});
       },
       [](rb::HybridEffectsDesc& d, const rb::RaySchedule& s) {
         d.effects = rb::kEffectAo;
         d.ao.schedule = s;
       }},
      {"ReflectionPass: ReflectionSettings::schedule", "HybridEffectsDesc::reflections.schedule",
       rb::kReflectionScheduleCapabilities, reflected.value().get(),
       [&](VkCommandBuffer cmd, const rb::RaySchedule& s) {
         rb::ReflectionSettings settings;
         settings.schedule = s;
         return reflection.value()->record(cmd, {.gbuffer = gbuffer.desc(), .tlas = built.tlas, .settings = settings});
       },
       [](rb::HybridEffectsDesc& d, const rb::RaySchedule& s) {
         d.effects = rb::kEffectReflections;
         d.reflections.schedule = s;
       }},
      {"ManyLightPass: ManyLightSettings::schedule", "HybridEffectsDesc::localLights.schedule",
       rb::kLocalLightScheduleCapabilities, rgb.value().get(),
       [&](VkCommandBuffer cmd, const rb::RaySchedule& s) {
         rb::ManyLightSettings settings;
         settings.schedule = s;
         return lights.value()->record(
             cmd, {.gbuffer = gbuffer.desc(), .tlas = built.tlas, .lights = list, .settings = settings});
       },
       [](rb::HybridEffectsDesc& d, const rb::RaySchedule& s) {
         d.effects = rb::kEffectLocalLights;
         d.localLights.schedule = s;
       }},
  };
  fx.runFrame([&](VkCommandBuffer cmd) {
    for (const Effect& e : effects) {
      for (const Damage& damage : damagesFor(e.allowed)) {
        INFO(e.field << " " << damage.member);
        rb::RaySchedule s;
        s.history = e.history;
        damage.apply(s);
        const rb::Status pass = e.record(cmd, s);
        INFO(pass.what());
        REQUIRE_FALSE(pass.ok());
        CHECK(pass.error().code == rb::ErrorCode::InvalidArgument);
        CHECK(std::string(pass.what()).find(std::string(e.field) + "." + damage.member) != std::string::npos);
        CHECK(occurrences(pass.what(), std::string(e.field).substr(std::string(e.field).find(": ") + 2)) == 1);

        rb::HybridEffectsDesc desc;
        e.describe(desc, s);
        auto front = rb::HybridEffects::create(fx.ctx(), service.value().get(), desc);
        INFO(front.what());
        REQUIRE_FALSE(front.ok());
        CHECK(std::string(front.what()).find(std::string(e.frontEndField) + "." + damage.member) != std::string::npos);
        CHECK(occurrences(front.what(), e.frontEndField) == 1);
      }
      // A schedule that needs the history names it when it is missing or of the wrong kind.
      rb::RaySchedule s;
      s.convergedTiles.enabled = true;
      const rb::Status missing = e.record(cmd, s);
      CHECK(std::string(missing.what()).find(std::string(e.field) + ".history is nullptr") != std::string::npos);
      s.history = e.history == scalar.value().get() ? rgb.value().get() : scalar.value().get();
      const rb::Status wrong = e.record(cmd, s);
      CHECK(std::string(wrong.what()).find(std::string(e.field) + ".history must be a DenoiseSignal::") !=
            std::string::npos);
    }
  });
  destroyScene(fx, built);
}
