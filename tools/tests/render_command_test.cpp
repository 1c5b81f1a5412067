// raybridge-render as a subprocess: bad input, half-resolution and reordered reflections, the frame budget and
// --compare-with, a dumped hybrid render
// with every effect (files, statistics, AO contact darkening), every preset in both modes, raster mode's
// counterparts. The validation layer is on; any error fails.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

#include <ImfRgbaFile.h>
#include <catch2/catch_approx.hpp>
#include <catch2/catch_test_macros.hpp>
#include <nlohmann/json.hpp>

#include "raybridge_sample_engine_adapter.h"
#include "render_command_support.h"
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

}  // namespace

TEST_CASE("raybridge-render rejects bad input with a message naming the problem", "[render][bad-input]") {
  const fs::path dir = tempDir("bad_input");
  struct Case {
    std::string args, expected;
  };
  const fs::path malformed = dir / "malformed.gltf";
  std::ofstream(malformed) << "{ \"asset\": { \"version\": \"2.0\" }, \"meshes\": [ { \"primitives\": ";
  // Each message names the option and the bad value, and the valid range or names.
  const std::vector<Case> cases = {
      {"--scene " + (dir / "missing.gltf").string(), "missing.gltf' does not exist"},
      {"--scene " + malformed.string(), "cannot load glTF"},
      {"--camera 1,2,3,1,2,3,45", "--camera: eye equals target"},
      {"--camera 1,2,3,0,0,0,180", "--camera: fovy 180 is outside [0.01, 180) degrees"},
      {"--width 0", "--width: 0 is outside 1..16384"},
      {"--height 100000", "--height: 100000 is outside 1..16384"},
      {"--width abc", "--width: 'abc' is not a whole number in 1..16384"},
      {"--sun 1,x,0", "--sun: 'x' in '1,x,0' is not a number"},
      {"--frobnicate", "unknown option '--frobnicate'"},
      {"stray", "unexpected argument 'stray'"},
      {"--preset nonsense", "--preset: 'nonsense' is not a preset (none, hard-shadows, ao, ao16, reflections, "
                            "soft-shadows, soft-shadows8, low, medium, high, ultra)"},
      {"--effects shadows,bogus",
       "--effects: 'bogus' in 'shadows,bogus' is not an effect (shadows, ao, reflections, lights)"},
      {"--light-rays 65", "--light-rays: 65 is outside 1..64 (or 0 = exact)"},
      {"--ao-rays 0", "--ao-rays: 0 is outside 1..4096"},
      {"--ao-range -1", "--ao-range: -1 must be greater than 0"},
      {"--ao-range abc", "--ao-range: 'abc' is not a number"},
      {"--ao-estimator cosine", "--ao-estimator: 'cosine' is not binary or distance"},
      {"--reflection-roughness 1.5", "--reflection-roughness: 1.5 is outside (0, 1]"},
      {"--reflection-rays 0", "--reflection-rays: 0 is outside 1..64"},
      {"--sun-radius 45", "--sun-radius: 45 is outside [0, 45) degrees"},
      {"--shadow-map-size 5", "--shadow-map-size: 5 is outside 1024..8192 (or 0 = no shadow map)"},
      {"--pcf 0", "--pcf: 0 is outside 1..9"},
      {"--mode fast", "--mode: 'fast' is not raster, hybrid or raytraced"},
      {"--mode raytraced --effects ao", "--effects: --mode raytraced shades every primary ray"},
      {"--mode raytraced --gbuffer-normals geometric", "--gbuffer-normals: --mode raytraced draws no G-buffer"},
      {"--adaptive reflections", "--adaptive: 'reflections' in 'reflections' is not an effect with adaptive rays"},
      {"--adaptive ao=-1", "--adaptive: '-1' in 'ao=-1' is not a time in ms greater than 0"},
      {"--adaptive ao=fast", "--adaptive: 'fast' in 'ao=fast' is not a time in ms"},
      {"--adaptive ao --no-denoise", "--adaptive: adaptive rays plan from the denoiser's history"},
      {"--adaptive ao,tile=3x4", "--adaptive: '3x4' in 'tile=3x4' is not a tile WxH with sides 1, 2, 4 or 8"},
      {"--adaptive ao,pixel=8x4", "--adaptive: '8x4' in 'pixel=8x4' is not allowed (pixel takes no size)"},
      {"--adaptive pixel", "--adaptive: 'pixel' names no effect with adaptive rays (shadows, ao)"},
      {"--budget 0", "--budget: 0 is outside (0, 1000] ms"},
      {"--budget -2", "--budget: -2 is outside (0, 1000] ms"},
      {"--budget nan", "--budget: 'nan' is not finite; give a finite number"},
      {"--budget inf", "--budget: 'inf' is not finite; give a finite number"},
      {"--budget 5000", "--budget: 5000 is outside (0, 1000] ms"},
      {"--budget fast", "--budget: 'fast' is not a number"},
      {"--budget 4 --adaptive ao", "--budget: the frame budget sets the adaptive rays' time targets itself"},
      {"--budget 4 --mode raster", "--budget: only --mode hybrid records the SDK's effects"},
      {"--compare-with .", "--compare-with: it compares the images --dump writes; add --dump"},
      {"--converged-tiles 0", "--converged-tiles: 0 is outside 1..65535"},
      {"--converged-tiles 8 --no-denoise", "--converged-tiles: converged tiles are read from the shadow denoiser's"},
      {"--converged-tiles 8 --no-converged-tiles", "--converged-tiles and --no-converged-tiles: give one of them"},
      {"--no-short-history-filter --no-denoise", "--no-short-history-filter: the filter is part of the AO denoiser"},
      {"--no-short-history-filter --mode raster",
       "--no-short-history-filter: only --mode hybrid denoises the SDK's AO"},
      {"--no-reset-rays --no-denoise", "--no-reset-rays: reset rays restart a denoiser's history"},
      {"--no-reset-rays --mode raster", "--no-reset-rays: only --mode hybrid traces the SDK's soft shadows and AO"},
      {"--reset-rays 8 --no-reset-rays", "--reset-rays and --no-reset-rays: give one of them"},
      {"--reset-follow-up 2 --no-reset-rays", "--reset-follow-up: follow-ups trace the reset rays"},
      {"--reset-follow-up 9", "--reset-follow-up: 9 is outside 0..8"},
      {"--reset-rays 0", "--reset-rays: 0 is outside 1..4096"},
      {"--no-reflection-changes --no-denoise",
       "--no-reflection-changes: only --mode hybrid's denoised reflections have a history to restart"},
      {"--reset-rays 5000", "--reset-rays: 5000 is outside 1..4096"},
      {"--converged-reflections 0", "--converged-reflections: 0 is outside 1..65535"},
      {"--converged-lights 8 --light-rays 0", "--converged-lights: --light-rays 0 traces every light exactly"},
      {"--converged-reflections 8 --no-denoise",
       "--converged-reflections: converged tiles are read from the reflection"},
      {"--converged-reflections 8 --half-res ao,reflections",
       "--converged-reflections: it skips tiles of full-resolution reflections: drop reflections from --half-res"},
      {"--half-res ao,shadows",
       "--half-res: 'shadows' in 'ao,shadows' is not an effect with half-resolution tracing (ao, reflections)"},
      {"--glossy-scene --perf-scene", "--glossy-scene is a scene of its own; it cannot be combined with --perf-scene"},
  };
  for (const Case& c : cases) {
    const RunResult r = runRender(c.args + " --out " + (dir / "out").string());
    INFO(c.args << "\n" << r.output);
    CHECK(r.exitCode != 0);
    CHECK(contains(r.output, c.expected));
  }
  {
    const RunResult r = runRender("--out " + (dir / "out").string() + " --width");  // the value is missing
    INFO(r.output);
    CHECK(r.exitCode != 0);
    CHECK(contains(r.output, "--width needs a value"));
  }
  CHECK_FALSE(fs::exists(dir / "out" / "final.png"));

  // --help (and -h) print the generated help, with every option and the presets, and exit 0 without rendering.
  for (const char* help : {"--help", "-h"}) {
    const RunResult r = runRender(std::string(help) + " --out " + (dir / "out").string());
    INFO(help << "\n" << r.output);
    CHECK(r.exitCode == 0);
    for (const char* part : {"Usage: raybridge-render", "--preset", "--effects", "--shadow-map-size", "--pcf",
                             "--dynamic-builds", "soft-shadows8"})
      CHECK(contains(r.output, part));
  }
  CHECK_FALSE(fs::exists(dir / "out" / "final.png"));
}

// Reads the R channel of an EXR written by raybridge-render.
using rbRenderTest::readExrRed;

TEST_CASE("raybridge-render --half-res traces AO and reflections at half resolution", "[render][halfres]") {
  // The same frames at full and at half resolution: the option reaches the SDK (the stats say so, and the passes
  // count about a quarter of the rays), and the images keep their size.
  auto render = [](const std::string& name, const std::string& halfRes) {
    const fs::path dir = tempDir(name);
    const RunResult r = runRender("--effects ao,reflections --width 96 --height 64 --dump --half-res " + halfRes +
                                  " --out " + dir.string());
    INFO(r.output);
    REQUIRE(r.exitCode == 0);
    int w = 0, h = 0;
    CHECK(readExrRed(dir / "ao.exr", w, h).size() == 96u * 64u);
    return nlohmann::json::parse(std::ifstream(dir / "stats.json"));
  };
  const nlohmann::json full = render("half_res_none", "none");
  const nlohmann::json half = render("half_res_both", "ao,reflections");
  CHECK(full["effects"]["ao_half_resolution"] == false);
  CHECK(full["effects"]["reflection_half_resolution"] == false);
  CHECK(half["effects"]["ao_half_resolution"] == true);
  CHECK(half["effects"]["reflection_half_resolution"] == true);
  CHECK(half["validation"]["errors"] == 0);
  for (const char* pass : {"ao", "reflection"}) {
    const double ratio = half["raybridge"]["passes"][pass]["rays"].get<double>() /
                         full["raybridge"]["passes"][pass]["rays"].get<double>();
    INFO(pass << ": half / full rays " << ratio);
    CHECK((ratio > 0.2 && ratio < 0.3));
  }
}

TEST_CASE("raybridge-render: the soft-shadow presets skip converged shadow tiles; --no-converged-tiles traces them",
          "[render][presets][converged]") {
  // A still camera for 24 frames: the shadow history converges and the preset's converged tiles skip some tiles.
  // --no-converged-tiles and --no-denoise (no history to read) trace every tile, as hard-shadows (no soft light).
  auto converged = [](const std::string& name, const std::string& extra) {
    const fs::path dir = tempDir(name);
    const RunResult r = runRender("--width 96 --height 64 --frames 24 --dump " + extra + " --out " + dir.string());
    INFO(extra << "\n" << r.output);
    REQUIRE(r.exitCode == 0);
    const nlohmann::json stats = nlohmann::json::parse(std::ifstream(dir / "stats.json"));
    CHECK(stats["validation"]["errors"] == 0);
    const nlohmann::json& shadow = stats["raybridge"]["passes"]["shadow"];
    return shadow.contains("tiles") ? shadow["tiles"]["converged"].get<uint64_t>() : uint64_t(0);
  };
  for (const char* preset : {"soft-shadows", "high"}) {
    INFO(preset);
    CHECK(converged(std::string("converged_") + preset, std::string("--preset ") + preset) > 0);
  }
  CHECK(converged("converged_off", "--preset high --no-converged-tiles") == 0);
  CHECK(converged("converged_no_denoise", "--preset high --no-denoise") == 0);
  CHECK(converged("converged_hard", "--preset hard-shadows") == 0);
}

TEST_CASE("raybridge-render --no-short-history-filter changes the denoised AO of a short history and nothing else",
          "[render][denoise]") {
  // Two frames: every pixel's history is short, so the AO denoiser's short-history filter is at work; without it the
  // denoised AO differs and the raw AO (the same rays) does not.
  auto render = [](const std::string& name, const std::string& extra) {
    const fs::path dir = tempDir(name);
    const RunResult r = runRender("--width 96 --height 64 --frames 2 --preset ao --dump " + extra + " --out " +
                                  dir.string());
    INFO(extra << "\n" << r.output);
    REQUIRE(r.exitCode == 0);
    return dir;
  };
  auto red = [](const fs::path& file) {
    int w = 0, h = 0;
    return readExrRed(file, w, h);
  };
  const fs::path withFilter = render("shf_on", ""), without = render("shf_off", "--no-short-history-filter");
  CHECK(red(withFilter / "ao_raw.exr") == red(without / "ao_raw.exr"));
  const std::vector<float> on = red(withFilter / "ao.exr"), off = red(without / "ao.exr");
  REQUIRE(on.size() == 96u * 64u);
  REQUIRE(off.size() == on.size());
  size_t differ = 0;
  for (size_t i = 0; i < on.size(); ++i) differ += on[i] != off[i];
  INFO(differ << " of " << on.size() << " denoised AO pixels differ");
  CHECK(differ > on.size() / 20);
}

TEST_CASE("raybridge-render --budget writes the frame budget's split; --compare-with scores a dump against another",
          "[render][budget]") {
  const fs::path none = tempDir("budget_none"), tight = tempDir("budget_tight"), same = tempDir("budget_same");
  const std::string common = "--width 96 --height 64 --frames 8 --preset high --dump ";
  RunResult r = runRender(common + "--out " + none.string());
  INFO(r.output);
  REQUIRE(r.exitCode == 0);
  r = runRender(common + "--budget 0.01 --compare-with " + none.string() + " --out " + tight.string());
  INFO(r.output);
  REQUIRE(r.exitCode == 0);
  const nlohmann::json s = rbRenderTest::readJson(tight / "stats.json");
  const nlohmann::json& b = s["raybridge"]["budget"];
  CHECK(b["budget_ms"].get<double>() == Catch::Approx(0.01));
  CHECK(b["below_floor"].get<bool>());           // no frame records in 10 microseconds
  CHECK(b["reflection_level"].get<int>() == 3);  // the render command's 4 glossy rays: 2, 1, then half resolution
  CHECK(b["measurements"].get<int>() >= 3);
  CHECK(s["raybridge"]["record_gpu_ms"].get<double>() > 0.0);
  // Every effect image differs from the unbudgeted one (fewer rays), by a finite error.
  for (const char* name : {"shadow", "ao", "reflection"}) {
    INFO(name);
    const double e = s["compare_with"]["images"][name]["rmse"].get<double>();
    CHECK(e > 0.0);
    CHECK(std::isfinite(e));
  }
  // The same run compared with itself: zero.
  r = runRender(common + "--compare-with " + none.string() + " --out " + same.string());
  INFO(r.output);
  REQUIRE(r.exitCode == 0);
  const nlohmann::json again = rbRenderTest::readJson(same / "stats.json");
  for (const char* name : {"shadow", "ao", "reflection"}) CHECK(again["compare_with"]["images"][name]["rmse"] == 0.0);
}

TEST_CASE("raybridge-render --reorder: stats.json says whether reflections reordered", "[render][reorder]") {
  auto render = [](const std::string& name, const std::string& extra) {
    const fs::path dir = tempDir(name);
    const RunResult r = runRender("--effects reflections --width 64 --height 48 --dump " + extra + " --out " +
                                  dir.string());
    INFO(r.output);
    REQUIRE(r.exitCode == 0);
    return nlohmann::json::parse(std::ifstream(dir / "stats.json"));
  };
  const nlohmann::json on = render("reorder_on", "--reorder");
  const nlohmann::json byDefault = render("reorder_default", "");
  // Reordered with --reorder exactly where the device enabled it (never on lavapipe); never by default.
  CHECK(on["effects"]["reflection_invocation_reorder"] == on["device"]["invocation_reorder"]);
  CHECK(byDefault["effects"]["reflection_invocation_reorder"] == false);
  CHECK(byDefault["device"]["invocation_reorder"] == on["device"]["invocation_reorder"]);  // the same device
  CHECK(on["validation"]["errors"] == 0);
}

TEST_CASE("raybridge-render: --preset high --dump writes every effect image and counts rays per pass", "[render]") {
  const fs::path dir = tempDir("dump");
  const int w = 160, h = 96;
  const RunResult r = runRender("--preset high --width 160 --height 96 --dump --out " + dir.string());
  INFO(r.output);
  REQUIRE(r.exitCode == 0);
  for (const char* name : {"final.png", "final.exr", "depth.exr", "normal.exr", "shadow.exr", "shadow_raw.exr",
                           "ao.exr", "ao_raw.exr", "reflection.exr", "lights.exr", "stats.json"}) {
    INFO(name);
    CHECK(fs::file_size(dir / name) > 0);
  }
  const nlohmann::json stats = nlohmann::json::parse(std::ifstream(dir / "stats.json"));
  CHECK(stats["mode"] == "hybrid");
  CHECK(stats["preset"] == "high");
  // The demo scene's punctual lights add the local lights effect to the preset's.
  CHECK(stats["effects"]["enabled"] == "shadows,ao,reflections,lights");
  CHECK(stats["lights"]["count"].get<uint32_t>() >= 4);
  CHECK(stats["lights"]["shadowed_by"] == "raybridge");
  CHECK(stats["width"] == w);
  CHECK(stats["rays_traced"].get<uint64_t>() > 0);
  const nlohmann::json& passes = stats["raybridge"]["passes"];
  for (const char* pass : {"shadow", "ao", "reflection", "local_lights"}) {
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

TEST_CASE("all eleven presets render in both modes; raster mode follows the preset's shadow map and PCF",
          "[render][presets]") {
  REQUIRE(rb::kPresetCount == 11);
  for (uint32_t i = 0; i < rb::kPresetCount; ++i) {
    const rb::Preset preset = rb::Preset(i);
    const rb::PresetDesc want = rb::presetDesc(preset);
    for (const char* mode : {"raster", "hybrid"}) {
      const fs::path dir = tempDir(std::string("preset_") + rb::toString(preset) + "_" + mode);
      const RunResult r = runRender(std::string("--mode ") + mode + " --preset " + rb::toString(preset) +
                                    " --width 64 --height 40 --frames 4 --dump --out " + dir.string());
      INFO(rb::toString(preset) << " " << mode << "\n" << r.output);
      REQUIRE(r.exitCode == 0);
      const nlohmann::json stats = nlohmann::json::parse(std::ifstream(dir / "stats.json"));
      CHECK(stats["preset"] == rb::toString(preset));
      CHECK(stats["validation"]["errors"] == 0);
      if (std::string(mode) == "raster") {
        // What the engine reports it drew (after its own clamping), not what was asked for.
        const nlohmann::json& raster = stats["effects"]["raster_counterparts"];
        CHECK(raster["shadow_map_size"] == want.raster.mapSize);
        CHECK(raster["pcf_kernel"] == (want.raster.mapSize ? std::max(1u, want.raster.pcfKernel) : 0u));
        CHECK(stats["rays_traced"] == 0);
        continue;
      }
      const nlohmann::json& passes = stats["raybridge"]["passes"];
      CHECK(passes.contains("shadow") == bool(want.effects & rb::kEffectShadows));
      CHECK(passes.contains("ao") == bool(want.effects & rb::kEffectAo));
      CHECK(passes.contains("reflection") == bool(want.effects & rb::kEffectReflections));
      CHECK(passes.contains("local_lights") == (preset != rb::Preset::None));  // the demo's punctual lights
      // Soft shadows (more than one ray) are denoised, hard ones never; the reported rays per pixel are the table's.
      CHECK(passes.contains("shadow_denoise") == (want.shadowRaysPerPixel > 1));
      if (want.effects & rb::kEffectShadows) CHECK(stats["sun"]["rays_per_pixel"] == want.shadowRaysPerPixel);
      if (want.effects & rb::kEffectAo) {
        CHECK(stats["effects"]["ao_rays_per_pixel"] == want.aoRaysPerPixel);
        CHECK(stats["effects"]["ao_half_resolution"] == want.aoHalfResolution);
      }
      if (want.effects == 0) CHECK(stats["rays_traced"] == 0);
      else
        CHECK(stats["rays_traced"].get<uint64_t>() > 0);
    }
  }
}

TEST_CASE("raybridge-render --mode raster uses the engine's shadow map, SSAO and reflection probe",
          "[render][raster]") {
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

TEST_CASE("raybridge-render --glossy-scene: 1M+ triangles, 70% of the pixels reflecting at roughness 0.2-0.5",
          "[render][glossy]") {
  // Issue 30's glossy scene as far as a small render can check it, from its own camera (the first keyframe of
  // scripts/gpu/glossy_path.json): its size, and the share of pixels that reflect at roughness 0.2-0.5. normal.exr's
  // A is the roughness the reflection pass reads; the raw reflection image tells which pixels traced (a pixel over
  // --reflection-roughness is written 0, one under it the light its rays brought back). A reflecting pixel whose
  // rays all brought back black would count as not reflecting, so the share is a lower bound.
  const fs::path dir = tempDir("glossy");
  const RunResult r = runRender("--glossy-scene --preset reflections --no-denoise --width 96 --height 64 --frames 3 "
                                "--dump --reflection-roughness 0.5 --out " +
                                dir.string());
  INFO(r.output);
  REQUIRE(r.exitCode == 0);
  const nlohmann::json stats = rbRenderTest::readJson(dir / "stats.json");
  REQUIRE_FALSE(stats.is_discarded());
  CHECK(stats["scene"] == "glossy scene");
  CHECK(stats["triangles"].get<uint64_t>() >= 1000000u);  // summed over instances: what the TLAS holds
  CHECK(stats["instances"].get<uint64_t>() >= 50u);
  CHECK(stats["raybridge"]["acceleration_structures"]["tlas_instances"] == stats["instances"]);
  CHECK(stats["raybridge"]["acceleration_structures"]["dedup_hits"].get<uint64_t>() > 0u);  // shared shapes
  CHECK(stats["raybridge"]["passes"]["reflection"]["rays"].get<uint64_t>() > 0u);
  CHECK(stats["validation"]["errors"] == 0);
  int w = 0, h = 0;
  const std::vector<float> reflection = rbRenderTest::readExrRgb(dir / "reflection.exr", w, h);
  const std::vector<float> normal = rbRenderTest::readExrRgb(dir / "normal.exr", w, h);
  const std::vector<float> roughness = rbRenderTest::readExrChannel(dir / "normal.exr", "A", w, h);
  REQUIRE((w == 96 && h == 64));
  REQUIRE((reflection.size() == normal.size() && roughness.size() * 3 == normal.size()));
  size_t surface = 0, glossy = 0, mirror = 0, reflectingOverThreshold = 0;
  for (size_t i = 0; i < size_t(w) * h; ++i) {
    surface += normal[3 * i] != 0.0f || normal[3 * i + 1] != 0.0f || normal[3 * i + 2] != 0.0f;  // the sky is 0
    const bool lit = reflection[3 * i] + reflection[3 * i + 1] + reflection[3 * i + 2] > 0.0f;
    const float a = roughness[i];
    glossy += lit && a >= 0.2f && a <= 0.5f;
    mirror += lit && a < 0.2f;
    reflectingOverThreshold += lit && a > 0.5f;  // the pass skips those: none may reflect
  }
  INFO(glossy << " glossy and " << mirror << " mirror pixels of " << surface << " surface pixels, " << w * h
              << " in all");
  CHECK(double(glossy) >= 0.7 * double(surface));
  CHECK(double(glossy) >= 0.7 * double(w) * double(h));  // the path keeps the sky out of view
  CHECK(mirror > 0u);                                    // a mirror for contrast
  CHECK(reflectingOverThreshold == 0u);
  fs::remove_all(dir);
}
