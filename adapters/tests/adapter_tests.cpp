// Tests of the sample-engine adapter and raybridge-render: bad input, a dumped hybrid render with every effect
// (files, statistics, AO contact darkening), raster vs hybrid shadows on the demo scene, pass memory that
// follows the enabled effects. The validation layer is on; any error fails.
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

#include <ImfRgbaFile.h>
#include <catch2/catch_test_macros.hpp>
#include <nlohmann/json.hpp>

#include "render_command_support.h"
#include "raybridge_sample_engine_adapter.h"
#include "sample_engine/procedural.h"

namespace fs = std::filesystem;
namespace se = sample_engine;

namespace {

struct RunResult {
  int exitCode = -1;
  std::string output;  // stdout and stderr
};

// The render command built with these tests; RAYBRIDGE_RENDER overrides it where the binaries were moved
// (the GPU machine runs a carried copy).
std::string renderExecutable() {
  const char* overridden = std::getenv("RAYBRIDGE_RENDER");
  return overridden && *overridden ? overridden : RAYBRIDGE_RENDER_EXE;
}

RunResult runRender(const std::string& args) {
  std::string command = "\"";
  command += renderExecutable();
  command += "\" --validation ";
  command += args;
  command += " 2>&1";
  RunResult r;
  FILE* pipe = popen(command.c_str(), "r");
  REQUIRE(pipe != nullptr);
  char buffer[4096];
  while (size_t n = fread(buffer, 1, sizeof buffer, pipe)) r.output.append(buffer, n);
  const int status = pclose(pipe);
  r.exitCode = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return r;
}

fs::path tempDir(const std::string& name) {
  fs::path dir = fs::temp_directory_path() / ("raybridge_adapter_tests_" + name);
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

bool contains(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }

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

TEST_CASE("raybridge-render rejects bad input with a message naming the problem", "[render][bad-input]") {
  const fs::path dir = tempDir("bad_input");
  struct Case {
    std::string args, expected;
  };
  const fs::path malformed = dir / "malformed.gltf";
  std::ofstream(malformed) << "{ \"asset\": { \"version\": \"2.0\" }, \"meshes\": [ { \"primitives\": ";
  const std::vector<Case> cases = {
      {"--scene " + (dir / "missing.gltf").string(), "missing.gltf' does not exist"},
      {"--scene " + malformed.string(), "cannot load glTF"},
      {"--camera 1,2,3,1,2,3,45", "eye equals target"},
      {"--width 0", "--width: 0 is outside"},
      {"--height 100000", "--height: 100000 is outside"},
      {"--width abc", "'abc' is not a whole number"},
      {"--sun 1,x,0", "'x' in '1,x,0' is not a number"},
      {"--frobnicate", "unknown option '--frobnicate'"},
      {"--preset nonsense", "--preset: 'nonsense' is not low, medium, high, ultra"},
      {"--effects shadows,bogus", "--effects: 'bogus' in 'shadows,bogus' is not an effect"},
      {"--effects ''", "--effects: the list is empty"},
      {"--ao-rays 0", "--ao-rays: 0 is outside 1..4096"},
      {"--ao-range -1", "--ao-range: -1 must be greater than 0"},
      {"--ao-range abc", "--ao-range: 'abc' is not a number"},
      {"--ao-estimator cosine", "--ao-estimator: 'cosine' is not binary or distance"},
      {"--reflection-roughness 1.5", "--reflection-roughness: 1.5 is outside (0, 1]"},
      {"--reflection-rays 0", "--reflection-rays: 0 is outside 1..64"},
  };
  for (const Case& c : cases) {
    const RunResult r = runRender(c.args + " --out " + (dir / "out").string());
    INFO(c.args << "\n" << r.output);
    CHECK(r.exitCode != 0);
    CHECK(contains(r.output, c.expected));
  }
  CHECK_FALSE(fs::exists(dir / "out" / "final.png"));
}

// Reads the R channel of an EXR written by raybridge-render.
using rbRenderTest::readExrRed;

TEST_CASE("raybridge-render: --preset high --dump writes every effect image and counts rays per pass", "[render]") {
  const fs::path dir = tempDir("dump");
  const int w = 160, h = 96;
  const RunResult r = runRender("--preset high --width 160 --height 96 --dump --out " + dir.string());
  INFO(r.output);
  REQUIRE(r.exitCode == 0);
  for (const char* name : {"final.png", "final.exr", "depth.exr", "normal.exr", "shadow.exr", "shadow_raw.exr", "ao.exr",
                           "ao_raw.exr", "reflection.exr", "stats.json"}) {
    INFO(name);
    CHECK(fs::file_size(dir / name) > 0);
  }
  const nlohmann::json stats = nlohmann::json::parse(std::ifstream(dir / "stats.json"));
  CHECK(stats["mode"] == "hybrid");
  CHECK(stats["preset"] == "high");
  CHECK(stats["effects"]["enabled"] == "shadows,ao,reflections");
  CHECK(stats["width"] == w);
  CHECK(stats["rays_traced"].get<uint64_t>() > 0);
  const nlohmann::json& passes = stats["raybridge"]["passes"];
  for (const char* pass : {"shadow", "ao", "reflection"}) {
    INFO(pass);
    REQUIRE(passes.contains(pass));
    CHECK(passes[pass]["rays"].get<uint64_t>() > 0);
    CHECK(passes[pass]["gpu_ms"].get<double>() > 0.0);
    CHECK(passes[pass]["rays_per_second"].get<double>() > 0.0);
  }
  for (const char* pass : {"shadow_denoise", "ao_denoise"}) {  // soft shadows and AO are denoised by default
    INFO(pass);
    REQUIRE(passes.contains(pass));
    CHECK(passes[pass]["gpu_ms"].get<double>() > 0.0);
  }
  const nlohmann::json& memory = stats["raybridge"]["memory_bytes"];
  CHECK(memory["pass_images"].get<uint64_t>() > 0);
  CHECK(memory["total"].get<uint64_t>() > 0);
  CHECK(stats["raybridge"]["acceleration_structures"]["tlas_instances"] == stats["instances"]);
  CHECK(stats["validation"]["errors"] == 0);

  const se::Camera camera = *se::makeDefaultDemoScene().camera;
  const glm::mat4 viewProj = se::projectionMatrix(camera, float(w) / float(h)) * se::viewMatrix(camera);

  // depth.exr holds the distance from the eye along the pixel-centre ray: check a ground pixel analytically.
  int dw = 0, dh = 0;
  const std::vector<float> depth = readExrRed(dir / "depth.exr", dw, dh);
  REQUIRE(dw == w);
  REQUIRE(dh == h);
  const glm::mat4 inv = glm::inverse(viewProj);
  const uint32_t px = 66, py = 94;  // bottom of the image: the ground plane y = 0
  const glm::vec2 ndc((px + 0.5f) / float(w) * 2.0f - 1.0f, (py + 0.5f) / float(h) * 2.0f - 1.0f);
  const glm::vec4 far = inv * glm::vec4(ndc, 1.0f, 1.0f);
  const glm::vec3 ray = glm::normalize(glm::vec3(far) / far.w - camera.eye);
  const float expected = -camera.eye.y / ray.y;
  CHECK(std::abs(depth[py * w + px] - expected) < 0.01f * expected);
  CHECK(depth[0] == 0.0f);  // top-left: sky

  // AO: the ground right in front of the gold sphere (radius 1 at (-1.6, 1, 0)) is darker than open ground.
  int aw = 0, ah = 0;
  const std::vector<float> ao = readExrRed(dir / "ao.exr", aw, ah);
  REQUIRE(aw == w);
  auto meanAround = [&](glm::vec3 world) {
    const glm::vec4 clip = viewProj * glm::vec4(world, 1.0f);
    const int x = int((clip.x / clip.w * 0.5f + 0.5f) * float(w)), y = int((clip.y / clip.w * 0.5f + 0.5f) * float(h));
    REQUIRE((x >= 1 && y >= 1 && x + 1 < w && y + 1 < h));
    float sum = 0.0f;
    for (int dy = -1; dy <= 1; ++dy)
      for (int dx = -1; dx <= 1; ++dx) sum += ao[size_t(y + dy) * w + size_t(x + dx)];
    return sum / 9.0f;
  };
  const float base = meanAround({-1.6f, 0.0f, 1.05f});
  const float open = meanAround({-2.5f, 0.0f, 6.0f});
  INFO("AO at the sphere's base " << base << ", on open ground " << open);
  CHECK(open > 0.9f);
  CHECK(base < open - 0.15f);
}

TEST_CASE("hybrid and raster shadow the same ground regions of the demo scene", "[adapter][shadows]") {
  auto engine = makeEngine();
  REQUIRE(engine->loadScene(se::makeDefaultDemoScene()).ok());
  const uint32_t w = 256, h = 144;
  REQUIRE(engine->setRenderSize(w, h).ok());
  auto adapter = rbAdapter::Adapter::create(*engine, {});
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
  CHECK(both > ground / 50);                  // there are shadows on the ground in both modes
  CHECK(double(both) / double(either) > 0.7);  // and they overlap substantially
  engine->setPrepassHook({});
  adapter.value.reset();
  CHECK(engine->validationErrorCount() == 0);
}

TEST_CASE("the adapter without effects allocates no pass images and builds nothing", "[adapter][memory]") {
  auto engine = makeEngine();
  REQUIRE(engine->loadScene(se::makeDefaultDemoScene()).ok());
  REQUIRE(engine->setRenderSize(64, 48).ok());
  rbAdapter::AdapterConfig config;
  config.effects = 0;
  auto adapter = rbAdapter::Adapter::create(*engine, config);
  INFO(adapter.error);
  REQUIRE(adapter.ok());
  CHECK(adapter.value->shadowPass() == nullptr);
  engine->setPrepassHook(adapter.value->prepassHook());
  se::FrameParams params;
  params.camera = *engine->scene().camera;
  for (int i = 0; i < 3; ++i) REQUIRE(engine->renderFrame(params).ok());
  REQUIRE(engine->waitIdle().ok());
  const rb::MemoryStats memory = adapter.value->context().memoryStats();
  CHECK(memory.of(rb::MemoryCategory::PassImages) == 0);
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
  auto adapter = rbAdapter::Adapter::create(*engine, {});
  REQUIRE(adapter.ok());
  engine->setPrepassHook(adapter.value->prepassHook());
  se::FrameParams params;
  params.camera = *engine->scene().camera;
  REQUIRE(engine->renderFrame(params).ok());
  REQUIRE(engine->waitIdle().ok());
  CHECK(adapter.value->context().memoryStats().of(rb::MemoryCategory::PassImages) >= 64 * 48 * 2);
  CHECK(adapter.value->lastTlas().instanceCount == engine->scene().instances.size());
  engine->setPrepassHook({});
  adapter.value.reset();
  CHECK(engine->validationErrorCount() == 0);
}

TEST_CASE("pass memory follows the enabled effects at run time", "[adapter][memory][effects]") {
  auto engine = makeEngine();
  REQUIRE(engine->loadScene(se::makeDefaultDemoScene()).ok());
  REQUIRE(engine->setRenderSize(64, 48).ok());
  auto created = rbAdapter::Adapter::create(*engine, {});  // shadows only
  INFO(created.error);
  REQUIRE(created.ok());
  rbAdapter::Adapter& adapter = *created.value;
  engine->setPrepassHook(adapter.prepassHook());
  se::FrameParams params;
  params.camera = *engine->scene().camera;
  params.sun = *engine->scene().sun;
  auto settle = [&] {  // frames in flight retire what was disabled; then release it while idle
    for (uint32_t i = 0; i < se::kFramesInFlight + 1; ++i) REQUIRE(engine->renderFrame(params).ok());
    REQUIRE(engine->waitIdle().ok());
    adapter.releaseAfterIdle();
    INFO(adapter.lastError());
    REQUIRE(adapter.lastError().empty());
    return adapter.context().memoryStats();
  };
  using C = rb::MemoryCategory;
  const rb::MemoryStats shadowOnly = settle();
  CHECK(shadowOnly.of(C::PassImages) >= 64 * 48 * 2);
  CHECK(shadowOnly.of(C::PassBuffers) > 0);
  CHECK(adapter.aoPass() == nullptr);
  CHECK(adapter.reflectionPass() == nullptr);

  REQUIRE(adapter.applyPreset(rbAdapter::Preset::Ultra).ok());  // all effects, soft shadows: two denoisers
  const rb::MemoryStats all = settle();
  CHECK(adapter.effects() == rbAdapter::kAllEffects);
  CHECK(adapter.aoPass() != nullptr);
  CHECK(adapter.reflectionPass() != nullptr);
  CHECK(adapter.shadowDenoiser() != nullptr);
  CHECK(adapter.aoDenoiser() != nullptr);
  // AO image + reflection image + two denoisers' history: well above the shadow-only images.
  CHECK(all.of(C::PassImages) >= shadowOnly.of(C::PassImages) + 64 * 48 * (2 + 8));
  CHECK(all.of(C::PassBuffers) > shadowOnly.of(C::PassBuffers));
  const rbAdapter::EffectStats stats = adapter.stats();
  CHECK(stats.ao.rays > 0);
  CHECK(stats.reflection.rays > 0);

  adapter.settings().denoise = false;  // the denoisers go, the passes stay
  const rb::MemoryStats raw = settle();
  CHECK(adapter.shadowDenoiser() == nullptr);
  CHECK(adapter.aoDenoiser() == nullptr);
  CHECK(raw.of(C::PassImages) < all.of(C::PassImages));

  REQUIRE(adapter.setEffects(rbAdapter::kEffectShadows).ok());
  const rb::MemoryStats back = settle();
  CHECK(adapter.aoPass() == nullptr);
  CHECK(adapter.reflectionPass() == nullptr);
  CHECK(back.of(C::PassImages) == shadowOnly.of(C::PassImages));
  CHECK(back.of(C::PassBuffers) == shadowOnly.of(C::PassBuffers));

  REQUIRE(adapter.setEffects(0).ok());
  const rb::MemoryStats none = settle();
  CHECK(adapter.shadowPass() == nullptr);
  CHECK(none.of(C::PassImages) == 0);
  CHECK(none.of(C::PassBuffers) == 0);

  engine->setPrepassHook({});
  created.value.reset();
  CHECK(engine->validationErrorCount() == 0);
}

TEST_CASE("effect names and presets", "[adapter][presets]") {
  rbAdapter::EffectSet set = 0;
  CHECK(rbAdapter::parseEffects("reflections,shadows", set).empty());
  CHECK(set == (rbAdapter::kEffectShadows | rbAdapter::kEffectReflections));
  CHECK(rbAdapter::effectsToString(set) == "shadows,reflections");
  CHECK(contains(rbAdapter::parseEffects("ao,shadow", set), "'shadow'"));
  for (const char* name : {"low", "medium", "high", "ultra", "shadows", "ao", "reflections"}) {
    INFO(name);
    const auto p = rbAdapter::parsePreset(name);
    REQUIRE(p.has_value());
    CHECK(std::string(rbAdapter::toString(*p)) == name);
  }
  CHECK_FALSE(rbAdapter::parsePreset("High").has_value());
  const rbAdapter::PresetDesc low = rbAdapter::presetDesc(rbAdapter::Preset::Low);
  CHECK(low.effects == (rbAdapter::kEffectShadows | rbAdapter::kEffectAo));
  CHECK_FALSE(low.softShadows);
  CHECK(low.aoRaysPerPixel == 4);
  const rbAdapter::PresetDesc ultra = rbAdapter::presetDesc(rbAdapter::Preset::Ultra);
  CHECK(ultra.effects == rbAdapter::kAllEffects);
  CHECK(ultra.shadowRaysPerPixel == 8);
  CHECK(ultra.aoRaysPerPixel == 16);
}

TEST_CASE("raybridge-render --mode raster uses the engine's shadow map, SSAO and reflection probe", "[render][raster]") {
  const fs::path dir = tempDir("raster");
  const RunResult r = runRender("--mode raster --preset high --width 96 --height 64 --dump --out " + dir.string());
  INFO(r.output);
  REQUIRE(r.exitCode == 0);
  for (const char* name : {"final.png", "shadow.exr", "ao.exr", "stats.json"}) {
    INFO(name);
    CHECK(fs::file_size(dir / name) > 0);
  }
  CHECK_FALSE(fs::exists(dir / "reflection.exr"));  // the probe is a cubemap, not a screen image
  const nlohmann::json stats = nlohmann::json::parse(std::ifstream(dir / "stats.json"));
  CHECK(stats["mode"] == "raster");
  CHECK(stats["effects"]["raster_counterparts"]["ao"] == "SSAO");
  CHECK(stats["effects"]["raster_counterparts"]["reflections"] == "reflection probe");
  CHECK(stats["rays_traced"] == 0);
  int w = 0, h = 0;
  const std::vector<float> shadow = readExrRed(dir / "shadow.exr", w, h);
  float minimum = 1.0f;
  for (float v : shadow) minimum = std::min(minimum, v);
  CHECK(minimum < 0.1f);  // the shadow map shadows something
}
