// Tests of the sample-engine adapter and raybridge-render: bad input, a dumped hybrid render, raster vs hybrid
// shadows on the demo scene, no pass memory without effects. The validation layer is on; any error fails.
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

#include <ImfRgbaFile.h>
#include <catch2/catch_test_macros.hpp>
#include <nlohmann/json.hpp>

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
  };
  for (const Case& c : cases) {
    const RunResult r = runRender(c.args + " --out " + (dir / "out").string());
    INFO(c.args << "\n" << r.output);
    CHECK(r.exitCode != 0);
    CHECK(contains(r.output, c.expected));
  }
  CHECK_FALSE(fs::exists(dir / "out" / "final.png"));
}

TEST_CASE("raybridge-render: a small hybrid render with --dump writes every file and counts rays", "[render]") {
  const fs::path dir = tempDir("dump");
  const RunResult r = runRender("--width 96 --height 64 --dump --out " + dir.string());
  INFO(r.output);
  REQUIRE(r.exitCode == 0);
  for (const char* name : {"final.png", "final.exr", "depth.exr", "normal.exr", "shadow.exr", "stats.json"}) {
    INFO(name);
    CHECK(fs::file_size(dir / name) > 0);
  }
  const nlohmann::json stats = nlohmann::json::parse(std::ifstream(dir / "stats.json"));
  CHECK(stats["mode"] == "hybrid");
  CHECK(stats["width"] == 96);
  CHECK(stats["rays_traced"].get<uint64_t>() > 0);
  CHECK(stats["raybridge"]["shadow_pass"]["gpu_ms"].get<double>() > 0.0);
  CHECK(stats["raybridge"]["acceleration_structures"]["tlas_instances"] == stats["instances"]);
  CHECK(stats["validation"]["errors"] == 0);

  // depth.exr holds the distance from the eye along the pixel-centre ray: check a ground pixel analytically.
  Imf::RgbaInputFile depthFile((dir / "depth.exr").c_str());
  const Imath::Box2i window = depthFile.dataWindow();
  REQUIRE(window.max.x + 1 == 96);
  std::vector<Imf::Rgba> depth(96 * 64);
  depthFile.setFrameBuffer(depth.data(), 1, 96);
  depthFile.readPixels(window.min.y, window.max.y);
  const se::Camera camera = *se::makeDefaultDemoScene().camera;
  const glm::mat4 inv = glm::inverse(se::projectionMatrix(camera, 96.0f / 64.0f) * se::viewMatrix(camera));
  const uint32_t px = 40, py = 62;  // bottom of the image: the ground plane y = 0
  const glm::vec2 ndc((px + 0.5f) / 96.0f * 2.0f - 1.0f, (py + 0.5f) / 64.0f * 2.0f - 1.0f);
  const glm::vec4 far = inv * glm::vec4(ndc, 1.0f, 1.0f);
  const glm::vec3 ray = glm::normalize(glm::vec3(far) / far.w - camera.eye);
  const float expected = -camera.eye.y / ray.y;
  CHECK(std::abs(float(depth[py * 96 + px].r) - expected) < 0.01f * expected);
  CHECK(float(depth[0].r) == 0.0f);  // top-left: sky
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
