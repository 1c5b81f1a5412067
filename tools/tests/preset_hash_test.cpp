// Every preset's images, bit for bit, against hashes recorded at a named commit (preset_image_hashes.json): the
// safety net of a change that must change no image (issue 31's redesign). raybridge-render renders the demo scene
// at a small size for each preset with --dump; every image it writes (final, depth, normal, shadow and
// shadow_raw, ao and ao_raw, reflection, lights and lights_raw) is hashed. The images are deterministic on one
// driver (two runs give the same bytes), not across drivers: on another driver than the one the hashes were recorded
// on, the test is skipped with a message. To record them again (after a change that is meant to change images, with
// the reason in its commit message): RAYBRIDGE_RECORD_PRESET_HASHES=1 raybridge_preset_hash_tests, then set
// "commit" in the file to the commit that made them.
//
// The ray schedule's stages (tile classifier, converged tiles, adaptive rays, half resolution) are rendered the same
// way, over enough frames for tiles to converge (kScheduleRuns). Adaptive rays with half-resolution AO are left out:
// when the budget runs out, which workgroup claims the last rays depends on the CPU threads' order on lavapipe, so
// two runs differ (half_res_test and adaptive_rays_test check that combination by its statistics instead).
#include <raybridge/presets.h>

#include <catch2/catch_approx.hpp>
#include <catch2/catch_test_macros.hpp>

#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>

#include "render_command_support.h"

namespace fs = std::filesystem;
using namespace rbRenderTest;

namespace {

constexpr uint32_t kWidth = 96, kHeight = 64;

// FNV-1a over the file's bytes, as 16 hex digits: enough to see any changed byte, no dependency.
std::string fileHash(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  uint64_t h = 1469598103934665603ull;
  for (unsigned char c : bytes) h = (h ^ c) * 1099511628211ull;
  char hex[17];
  std::snprintf(hex, sizeof hex, "%016llx", static_cast<unsigned long long>(h));
  return hex;
}

// Each scheduling stage, alone and combined, on the effect it serves: every one of them must give the same images.
struct ScheduleRun {
  const char* name;
  const char* arguments;
};
constexpr ScheduleRun kScheduleRuns[] = {
    {"shadows-classifier", "--preset soft-shadows --tile-classifier --frames 4"},
    {"shadows-converged", "--preset soft-shadows --converged-tiles 4 --frames 24"},
    {"shadows-adaptive", "--preset soft-shadows --adaptive shadows --frames 4"},
    {"shadows-adaptive-pixel", "--preset soft-shadows --adaptive shadows,pixel --frames 4"},
    {"ao-converged-adaptive", "--preset ao --half-res none --converged-ao 4 --adaptive ao,tile=8x4 --frames 24"},
    {"reflections-half", "--preset reflections --half-res reflections --frames 4"},
    {"reflections-converged", "--preset reflections --converged-reflections 4 --frames 24"},
    {"lights-converged",
     "--preset medium --no-converged-tiles --effects shadows,lights --converged-lights 4 --frames 24"},
    {"high-adaptive-shadows", "--preset high --adaptive shadows --frames 6"},
};

// The hashes of one render's dumped images, by file name (stats.json, with its timings, and final.png left out).
// `stats`, when given, receives the render's stats.json.
nlohmann::json renderHashes(const std::string& name, const std::string& arguments, std::string& driver,
                            nlohmann::json* stats = nullptr) {
  const fs::path out = fs::temp_directory_path() / ("raybridge_preset_hash_" + name);
  fs::remove_all(out);
  const int status = runRender("--width " + std::to_string(kWidth) + " --height " + std::to_string(kHeight) + " " +
                               arguments + " --dump --out \"" + out.string() + "\" > /dev/null");
  REQUIRE(status == 0);
  const nlohmann::json read = readJson(out / "stats.json");
  REQUIRE_FALSE(read.is_discarded());
  driver = read["device"]["name"].get<std::string>() + " / " + read["device"]["driver_info"].get<std::string>();
  if (stats) *stats = read;
  nlohmann::json hashes = nlohmann::json::object();
  for (const fs::directory_entry& e : fs::directory_iterator(out)) {
    // final.png is final.exr through the engine's display pass, a fragment shader whose 8-bit rounding follows the
    // CPU features lavapipe's JIT compiles for (two machines with one driver string gave different bytes); the EXR
    // holds the same frame.
    if (e.path().filename() == "stats.json" || e.path().filename() == "final.png") continue;
    hashes[e.path().filename().string()] = fileHash(e.path());
  }
  fs::remove_all(out);
  return hashes;
}

}  // namespace

TEST_CASE("every preset renders the images recorded at the named commit, bit for bit", "[render][presets][golden]") {
  const fs::path file = fs::path(RAYBRIDGE_PRESET_HASHES);
  const bool record = std::getenv("RAYBRIDGE_RECORD_PRESET_HASHES") != nullptr;
  nlohmann::json recorded = readJson(file);
  if (!record) REQUIRE_FALSE(recorded.is_discarded());

  nlohmann::json now = {{"size", {kWidth, kHeight}}, {"presets", nlohmann::json::object()}};
  std::string driver;
  for (uint32_t i = 0; i < rb::kPresetCount; ++i) {
    const std::string preset = rb::toString(rb::Preset(i));
    now["presets"][preset] = renderHashes(preset, "--preset " + preset, driver);
    if (i == 0 && !record && recorded["driver"] != driver) {
      SKIP("the hashes were recorded on " << recorded["driver"].get<std::string>() << " (commit "
                                          << recorded["commit"].get<std::string>() << "), this is " << driver
                                          << ": images are bit-identical on one driver only");
    }
  }
  for (const ScheduleRun& run : kScheduleRuns) now["presets"][run.name] = renderHashes(run.name, run.arguments, driver);
  now["driver"] = driver;
  if (record) {
    now["commit"] = "set to the commit that made these images";
    std::ofstream(file) << now.dump(2) << "\n";
    WARN("recorded " << file.string() << " on " << driver << ": set its \"commit\"");
    return;
  }
  INFO("hashes of commit " << recorded["commit"].get<std::string>() << " on " << driver);
  CHECK(recorded["size"] == now["size"]);
  for (const auto& [preset, images] : recorded["presets"].items()) {
    INFO("preset " << preset);
    REQUIRE(now["presets"].contains(preset));
    for (const auto& [image, hash] : images.items()) {
      INFO("image " << image);
      CHECK(now["presets"][preset].value(image, std::string("missing")) == hash.get<std::string>());
    }
    CHECK(now["presets"][preset].size() == images.size());  // no image appeared or vanished
  }
  CHECK(now["presets"].size() == recorded["presets"].size());
}

// Transient aliasing (HybridEffectsDesc::disableTransientAliasing) changes no image: every preset's images over four
// frames, with the denoisers sharing one DenoiserScratch and with each keeping its own, are the same bytes. Unlike the
// recorded hashes this holds on any driver. The switch must really switch: the unaliased run holds each scratch
// image once per denoiser of its kind.
TEST_CASE("every preset's images are bit-identical with transient aliasing on and off", "[render][presets][aliasing]") {
  std::string driver;
  for (uint32_t i = 0; i < rb::kPresetCount; ++i) {
    const std::string preset = rb::toString(rb::Preset(i));
    INFO("preset " << preset);
    nlohmann::json statsOn, statsOff;
    const nlohmann::json on = renderHashes(preset + "-aliased", "--preset " + preset + " --frames 4", driver, &statsOn);
    const nlohmann::json off = renderHashes(preset + "-unaliased", "--preset " + preset + " --frames 4 --no-aliasing",
                                            driver, &statsOff);
    REQUIRE(on.size() > 2);  // the dump wrote its images
    CHECK(on == off);
    // The scratch holds one set of images per kind of denoiser (scalar: shadows, AO; RGB: reflections, local
    // lights): sharing saves memory where two of one kind run.
    const nlohmann::json& passes = statsOn["raybridge"]["passes"];
    const bool twoScalar = passes.contains("shadow_denoise") && passes.contains("ao_denoise");
    const bool twoRgb = passes.contains("reflection_denoise") && passes.contains("local_lights_denoise");
    const double bppOn = statsOn["raybridge"]["memory_bytes"]["pass_image_bytes_per_pixel"].get<double>();
    const double bppOff = statsOff["raybridge"]["memory_bytes"]["pass_image_bytes_per_pixel"].get<double>();
    INFO("pass images per pixel: aliased " << bppOn << ", unaliased " << bppOff);
    // Per pixel of the 96x64 dump: the scalar scratch RG16F (4 B), the RGB one RGBA16F + RG32UI (16 B).
    CHECK(bppOff - bppOn == Catch::Approx((twoScalar ? 4.0 : 0.0) + (twoRgb ? 16.0 : 0.0)).margin(0.01));
  }
}
