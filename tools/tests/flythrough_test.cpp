// The fly-through measurement of docs/performance.md: per-frame GPU time percentiles (tools/common/frame_series.h)
// against a hand-computed nearest rank, raybridge-render's frame_series in stats.json along a camera path, and the
// performance scene (--perf-scene), with its bad uses.
#include <catch2/catch_test_macros.hpp>

#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "frame_series.h"
#include "render_command_support.h"

namespace fs = std::filesystem;
using rbRenderTest::readJson;
using rbRenderTest::renderOutput;

namespace {

fs::path tempDir(const std::string& name) { return fs::temp_directory_path() / ("raybridge_flythrough_" + name); }

// The shared glTF models beside the checkout, as the render command finds them by default.
fs::path sharedScenes() { return fs::path(RAYBRIDGE_SOURCE_DIR) / ".." / "shared" / "scenes"; }

}  // namespace

TEST_CASE("frame series: nearest-rank percentiles after the warm-up, one sample per frame", "[flythrough]") {
  // Nearest rank: p50 of 1..10 is the 5th value, p99 the 10th; of 1..200, p99 is the 198th.
  std::vector<double> ten{7, 3, 9, 1, 10, 2, 8, 4, 6, 5};
  CHECK(rbRender::percentile(ten, 50.0) == 5.0);
  CHECK(rbRender::percentile(ten, 99.0) == 10.0);
  CHECK(rbRender::percentile(ten, 0.0) == 1.0);
  std::vector<double> many;
  for (int i = 200; i >= 1; --i) many.push_back(double(i));
  CHECK(rbRender::percentile(many, 99.0) == 198.0);
  CHECK(rbRender::percentile(many, 50.0) == 100.0);
  CHECK(rbRender::percentile({}, 50.0) == 0.0);

  rbRender::FrameSeries series;
  // Frames 1..3 are the warm-up (values 100 that must not show), then 4..13 with 1..10 ms; each frame offered twice
  // (a caller polls after every submit) and one older frame offered late: only the first of each counts.
  for (uint64_t f = 1; f <= 13; ++f) {
    const double ms = f <= rbRender::kFrameSeriesWarmupFrames ? 100.0 : double(f - 3);
    series.add("hook_gpu_ms", f, ms);
    series.add("hook_gpu_ms", f, 1000.0);
    if (f == 8) series.add("hook_gpu_ms", 2, 1000.0);
  }
  series.add("short_gpu_ms", 1, 5.0);  // only warm-up frames: left out
  const nlohmann::json s = series.summary();
  INFO(s.dump(2));
  REQUIRE(s.contains("hook_gpu_ms"));
  CHECK_FALSE(s.contains("short_gpu_ms"));
  CHECK(s["frames"] == 10);
  CHECK(s["hook_gpu_ms"]["samples"] == 10);
  CHECK(s["hook_gpu_ms"]["p50"] == 5.0);
  CHECK(s["hook_gpu_ms"]["p99"] == 10.0);
  CHECK(s["hook_gpu_ms"]["max"] == 10.0);
  CHECK(s["hook_gpu_ms"]["mean"] == 5.5);
}

TEST_CASE("raybridge-render along a camera path reports per-frame percentiles", "[flythrough][render]") {
  const fs::path dir = tempDir("path");
  fs::remove_all(dir);
  fs::create_directories(dir);
  const fs::path pathFile = dir / "fly.json";
  std::ofstream(pathFile) << R"({"version": 1, "keyframes": [
    {"position": [0, 3, 12], "orientation": [-0.1305, 0, 0, 0.9914], "duration": 1},
    {"position": [4, 2, 9], "orientation": [-0.1, 0.2, 0.02, 0.97]}]})";
  for (const char* mode : {"hybrid", "raster", "raytraced"}) {
    DYNAMIC_SECTION(mode) {
      int status = 0;
      const std::string out = renderOutput("--camera-path \"" + pathFile.string() + "\" --mode " + mode +
                                               " --preset low --width 64 --height 40 --frames 9 --dump --out \"" +
                                               (dir / mode).string() + "\"",
                                           status);
      INFO(out);
      REQUIRE(status == 0);
      const nlohmann::json stats = readJson(dir / mode / "stats.json");
      REQUIRE(stats.is_object());
      const nlohmann::json& fs = stats["frame_series"];
      INFO(fs.dump(2));
      // Nine frames: the last captures the images (--dump) and is not timed, the first three are the warm-up. The
      // engine resolves a frame when its slot is reused and, at the final wait, reports the newest only: the one
      // frame before the last timed one is never seen (two frames in flight).
      const int expected = 9 - 1 - int(rbRender::kFrameSeriesWarmupFrames) - 1;
      CHECK(fs["frames"] == expected);
      for (const char* metric : {"frame_gpu_ms", "hook_gpu_ms"}) {
        REQUIRE(fs.contains(metric));
        CHECK(fs[metric]["samples"] == expected);
        CHECK(fs[metric]["p50"].get<double>() <= fs[metric]["p99"].get<double>());
        CHECK(fs[metric]["p99"].get<double>() <= fs[metric]["max"].get<double>());
      }
      CHECK(fs["frame_gpu_ms"]["p50"].get<double>() > 0.0);
      if (std::string(mode) == "hybrid") {
        // The SDK's passes resolve frames in flight later, but the final wait collects them all.
        REQUIRE(fs.contains("shadow_gpu_ms"));
        REQUIRE(fs.contains("ao_gpu_ms"));
        // The SDK resolves a pass's frame once a later frame begins: the last frames of the run stay unresolved.
        CHECK(fs["shadow_gpu_ms"]["samples"].get<int>() >= expected - 2);
        CHECK(fs["hook_gpu_ms"]["p50"].get<double>() > 0.0);
      } else if (std::string(mode) == "raytraced") {
        // The primary shading pass is the hook's work; the engine draws no raster shading around it.
        REQUIRE(fs.contains("primary_shading_gpu_ms"));
        CHECK(fs["primary_shading_gpu_ms"]["samples"].get<int>() >= expected - 2);
        CHECK_FALSE(fs.contains("shadow_gpu_ms"));
        CHECK(fs["hook_gpu_ms"]["p50"].get<double>() > 0.0);
      } else {
        CHECK_FALSE(fs.contains("shadow_gpu_ms"));
        CHECK(fs["hook_gpu_ms"]["max"].get<double>() < fs["frame_gpu_ms"]["p50"].get<double>());
      }
    }
  }
}

TEST_CASE("raybridge-render --perf-scene composes the shared models on a fine ground", "[flythrough][render]") {
  if (!fs::is_regular_file(sharedScenes() / "ReciprocatingSaw" / "ReciprocatingSaw.gltf")) {
    SKIP("the shared glTF models are not at " + sharedScenes().string());
  }
  const fs::path dir = tempDir("perf_scene");
  fs::remove_all(dir);
  int status = 0;
  const std::string out = renderOutput(
      "--perf-scene --preset hard-shadows --width 64 --height 36 --frames 4 --dump --out \"" + dir.string() + "\"",
      status);
  INFO(out);
  REQUIRE(status == 0);
  const nlohmann::json stats = readJson(dir / "stats.json");
  REQUIRE(stats.is_object());
  CHECK(stats["scene"] == "performance scene");
  // The ground alone is 2 * 768^2 triangles; the models add well over a million more, in hundreds of instances.
  CHECK(stats["triangles"].get<uint64_t>() >= 2ull * 768 * 768 + 1000000ull);
  CHECK(stats["instances"].get<uint64_t>() >= 100);
  CHECK(stats["raybridge"]["acceleration_structures"]["tlas_instances"] == stats["instances"]);
  CHECK(stats["raybridge"]["passes"]["shadow"]["rays"].get<uint64_t>() > 0);
  CHECK(stats["validation"]["errors"] == 0);
}

TEST_CASE("raybridge-render --perf-scene: bad uses name the option", "[flythrough][render][bad-input]") {
  const fs::path dir = tempDir("bad");
  fs::create_directories(dir / "no_models_here");  // a folder without the models (a missing one fails before)
  struct Case {
    std::string args, expected;
  };
  const Case cases[] = {
      {"--perf-scene --scene x.gltf", "--perf-scene is a scene of its own"},
      {"--perf-scene --characters 2", "--perf-scene is a scene of its own"},
      {"--models-from /tmp", "--models-from needs --characters N or --perf-scene"},
      {"--perf-scene --models-from \"" + (dir / "no_models_here").string() + "\"",
       "no model of the performance scene found"},
  };
  for (const Case& c : cases) {
    int status = 0;
    const std::string out = renderOutput(c.args + " --width 32 --height 32 --out \"" + dir.string() + "\"", status);
    INFO(c.args << "\n" << out);
    CHECK(status != 0);
    CHECK(out.find(c.expected) != std::string::npos);
  }
}
