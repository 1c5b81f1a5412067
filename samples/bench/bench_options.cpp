// Command-line parsing of raybridge-bench, through CLI11 (samples/common/cli_support.h).
#include "bench_options.h"

#include "cli_support.h"

namespace rbbench {

const std::vector<std::string>& scenarioNames() {
  static const std::vector<std::string> names = {"build",      "duplication", "fastbuild-vs-fasttrace",
                                                 "compaction", "tlas",        "tlas-motion",
                                                 "trace",      "gigarays",    "alpha",
                                                 "lights",     "soak",        "memory"};
  return names;
}

namespace {

void addOptions(CLI::App& app, BenchOptions& o) {
  rbCli::prepare(app);
  app.description("Measures the acceleration-structure service in the scenarios of the hybrid ray tracing thesis.");
  std::vector<std::string> scenarios = scenarioNames();
  scenarios.push_back("all");
  app.add_option("--scenario", o.scenario,
                 "scenario to run: " + rbCli::joinNames(scenarios) + " (default all: every one but soak and memory)")
      ->type_name("NAME")
      ->check(rbCli::oneOf(scenarios));
  app.add_option("--out", o.outPath, "JSON report (default: none)")->type_name("FILE.json");
  app.add_flag("--quick", o.quick,
               "smallest sizes, fewest repeats (smoke test); soak: " + std::to_string(kQuickSoakFrames) +
                   " small frames");
  app.add_flag("--full", o.full, "GPU sizes (1M triangles) even on a CPU device");
  app.add_option("--width", o.width, "trace width, with --height; default 1920x1080 on a GPU, 640x360 on a\nCPU device")
      ->type_name("W")
      ->check(rbCli::wholeNumber(1, 16384));
  app.add_option("--height", o.height, "trace height")->type_name("H")->check(rbCli::wholeNumber(1, 16384));
  app.add_option("--device", o.device,
                 "case-insensitive substring of the device name (else $RAYBRIDGE_DEVICE, else\nautomatic)")
      ->type_name("SUBSTR");
  app.add_option("--scenes", o.scenesDir,
                 "folder of glTF models, one per subfolder (default: ../shared/scenes beside the\nsource tree)")
      ->type_name("DIR");
  app.add_option(
         "--images", o.imagesDir,
         "folder (created if missing) for tonemapped PNGs of the lights scenario's 256-light case:\nexact, raw and "
         "denoised (default: none)")
      ->type_name("DIR");
  app.add_option("--frames", o.frames,
                 "soak: frames to run (default " + std::to_string(kDefaultSoakFrames) + ", " +
                     std::to_string(kQuickSoakFrames) + " with --quick)")
      ->type_name("N")
      ->check(rbCli::wholeNumber(100, 100000000));
  app.add_option("--seed", o.seed,
                 "soak: seed of the random operations (default " + std::to_string(kDefaultSoakSeed) + ")")
      ->type_name("S")
      ->check(rbCli::wholeNumber(0, UINT64_MAX));
}

}  // namespace

std::string usage() {
  BenchOptions unused;
  CLI::App app{"", "raybridge-bench"};
  addOptions(app, unused);
  return app.help();
}

bool parseOptions(int argc, char** argv, BenchOptions& o, std::string& error) {
  o.scenesDir = std::string(RAYBRIDGE_SOURCE_DIR) + "/../shared/scenes";
  o.commandLine = rbCli::commandLine(argc, argv);
  CLI::App app{"", "raybridge-bench"};
  addOptions(app, o);
  error = rbCli::parse(app, argc, argv, o.help);
  if (!error.empty()) return false;
  if (o.help) return true;
  if ((o.width == 0) != (o.height == 0)) {
    error = "--width and --height go together";
    return false;
  }
  if (o.quick && o.full) {
    error = "--quick and --full exclude each other";
    return false;
  }
  return true;
}

}  // namespace rbbench
