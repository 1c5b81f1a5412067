// rb::LightList: the engine's lights uploaded once a frame and read by every effect lit by them (the many-light pass,
// reflection hits, the pure ray-traced mode), instead of one effect reading another's state. The many-light pass
// must light the same from a shared list as from the array itself, and a list that is stale, recorded twice or in
// another TLAS space is refused by name before anything is recorded.
#include <catch2/catch_test_macros.hpp>

#include <cstring>
#include <string>
#include <vector>

#include "many_light_scene.h"
#include "synthetic_gbuffer.h"

using namespace rbtest;

namespace {

bool contains(const rb::Status& s, const std::string& part) {
  return !s.ok() && s.error().message.find(part) != std::string::npos;
}

}  // namespace

TEST_CASE("the many-light pass lights the same from a shared LightList as from the array",
          "[light_list][many_lights]") {
  GpuFixture fx;
  TestScene scene = makeRoom();
  EmbreeScene embree;
  addToEmbree(embree, scene);
  CpuGBuffer cpu = traceGBuffer(embree, roomView(48, 36));
  const std::vector<rb::LightSource> lights = manyRoomLights();
  auto fromArray = rb::ManyLightPass::create(fx.ctx());
  auto fromList = rb::ManyLightPass::create(fx.ctx());
  auto list = rb::LightList::create(fx.ctx());
  RB_REQUIRE_OK(fromArray);
  RB_REQUIRE_OK(fromList);
  RB_REQUIRE_OK(list);
  CHECK(list.value()->info().frame == rb::kNeverRecorded);
  for (rb::ManyLightMode mode : {rb::ManyLightMode::Exact, rb::ManyLightMode::Stochastic}) {
    INFO("mode " << uint32_t(mode));
    rb::ManyLightSettings settings;
    settings.mode = mode;
    std::vector<float> a, b;
    runPassFrame(
        fx, scene, cpu, false,
        [&](VkCommandBuffer cmd, const rb::GBufferDesc& desc, const rb::TlasInfo& tlas) {
          RB_REQUIRE_OK(list.value()->record(cmd, tlas, lights));
          const rb::LightListInfo info = list.value()->info();
          CHECK(info.count == lights.size());
          CHECK(info.frame == fx.ctx().frameIndex());
          CHECK(info.buffer != VK_NULL_HANDLE);
          RB_REQUIRE_OK(
              fromArray.value()->record(cmd, {.gbuffer = desc, .tlas = tlas, .lights = lights, .settings = settings}));
          RB_REQUIRE_OK(fromList.value()->record(
              cmd, {.gbuffer = desc, .tlas = tlas, .lightList = list.value().get(), .settings = settings}));
        },
        [&](const rb::GBufferDesc& desc) {
          a = readRgba16f(fx, fromArray.value()->outputs().irradiance, desc.width, desc.height);
          b = readRgba16f(fx, fromList.value()->outputs().irradiance, desc.width, desc.height);
        });
    REQUIRE(a.size() == b.size());
    uint32_t lit = 0, differ = 0;
    for (size_t i = 0; i < a.size(); i += 4) {
      lit += a[i] > 0.0f || a[i + 1] > 0.0f || a[i + 2] > 0.0f;
      differ += std::memcmp(&a[i], &b[i], 4 * sizeof(float)) != 0;
    }
    INFO("lit pixels " << lit << ", differing " << differ);
    CHECK(lit > a.size() / 8);  // the lights reach the room
    CHECK(differ == 0);         // same lights, same seeds: the same bits
    CHECK(fromArray.value()->stats().rays == fromList.value()->stats().rays);
  }
}

TEST_CASE("a LightList is refused when stale, recorded twice or in another TLAS space; bad lights name the index",
          "[light_list][bad_input]") {
  GpuFixture fx;
  TestScene scene = makeRoom();
  EmbreeScene embree;
  addToEmbree(embree, scene);
  CpuGBuffer cpu = traceGBuffer(embree, roomView(32, 24));
  auto list = rb::LightList::create(fx.ctx());
  auto pass = rb::ManyLightPass::create(fx.ctx());
  RB_REQUIRE_OK(list);
  RB_REQUIRE_OK(pass);
  std::vector<rb::LightSource> lights = roomLights();
  uint64_t recordedIn = rb::kNeverRecorded;
  runPassFrame(
      fx, scene, cpu, false,
      [&](VkCommandBuffer cmd, const rb::GBufferDesc& desc, const rb::TlasInfo& tlas) {
        // Never recorded yet.
        CHECK(contains(pass.value()->record(cmd, {.gbuffer = desc, .tlas = tlas, .lightList = list.value().get()}),
                       "ManyLightPass: ManyLightFrame::lightList: that LightList was not recorded this frame"));
        CHECK(contains(list.value()->record(VK_NULL_HANDLE, tlas, lights), "LightList::record: cmd is VK_NULL_HANDLE"));
        // Bad lights: the index and field, and the list stays unrecorded.
        std::vector<rb::LightSource> bad = lights;
        bad[1].intensity = -1.0f;
        CHECK(contains(list.value()->record(cmd, tlas, bad), "LightList::record: lights[1]: intensity"));
        bad = lights;
        bad[2].light.position[0] = NAN;
        CHECK(contains(list.value()->record(cmd, tlas, bad),
                       "LightList::record: lights[2]: Light::position must be finite"));
        CHECK(contains(list.value()->record(cmd, tlas, std::vector<rb::LightSource>(70000, lights[0])),
                       "70000 lights exceed kMaxLights"));
        CHECK(list.value()->info().frame == rb::kNeverRecorded);
        // Recorded: readable this frame in its own TLAS space, once.
        RB_REQUIRE_OK(list.value()->record(cmd, tlas, lights));
        recordedIn = fx.ctx().frameIndex();
        CHECK(contains(list.value()->record(cmd, tlas, lights), "already recorded in frame"));
        rb::TlasInfo moved = tlas;
        moved.originOffset[0] += 4.0;
        CHECK(contains(pass.value()->record(cmd, {.gbuffer = desc, .tlas = moved, .lightList = list.value().get()}),
                       "recorded for another TLAS space"));
        RB_REQUIRE_OK(pass.value()->record(cmd, {.gbuffer = desc, .tlas = tlas, .lightList = list.value().get()}));
      },
      [](const rb::GBufferDesc&) {});
  CHECK(list.value()->info().frame == recordedIn);
  // The next frame: last frame's list is stale.
  runPassFrame(
      fx, scene, cpu, false,
      [&](VkCommandBuffer cmd, const rb::GBufferDesc& desc, const rb::TlasInfo& tlas) {
        CHECK(contains(pass.value()->record(cmd, {.gbuffer = desc, .tlas = tlas, .lightList = list.value().get()}),
                       "not recorded this frame"));
      },
      [](const rb::GBufferDesc&) {});
}
