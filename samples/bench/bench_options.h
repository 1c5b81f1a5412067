// Command line of raybridge-bench.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace rbbench {

// Defaults of the soak scenario's --frames and --seed.
inline constexpr uint32_t kDefaultSoakFrames = 10000;
inline constexpr uint32_t kQuickSoakFrames = 2000;
inline constexpr uint64_t kDefaultSoakSeed = 20261202;

struct BenchOptions {
  std::string scenario = "all";  // one of scenarioNames() or "all" (every one but "soak" and "memory")
  std::string outPath;           // empty = no JSON file
  bool quick = false;            // smallest sizes and fewest repeats (smoke test, under ~2 minutes on lavapipe)
  bool full = false;             // the GPU sizes even on a CPU device (1M triangles, ...)
  uint32_t width = 0;            // 0 = automatic: 1920x1080 on a GPU, smaller on a CPU device
  uint32_t height = 0;
  std::string device;     // substring of the device name; empty = $RAYBRIDGE_DEVICE or automatic
  std::string scenesDir;  // glTF models, one folder each; default <source>/../shared/scenes
  std::string imagesDir;  // lights scenario's pictures (PNG); empty = none
  uint32_t frames = 0;    // soak scenario: frames to run; 0 = kDefaultSoakFrames (kQuickSoakFrames with --quick)
  uint64_t seed = kDefaultSoakSeed;  // soak scenario: seed of its random operations
  std::string commandLine;           // as typed, for the report
  bool help = false;
};

// The scenarios, in the order they run. "all" runs every one but "soak" and "memory", which run only when named
// (they measure no speed; the soak takes minutes, the memory sweep a minute on lavapipe with --quick when the driver
// compiles its pipelines afresh).
const std::vector<std::string>& scenarioNames();
// The help CLI11 generates for these options.
std::string usage();
// Parses argv; returns false with a message in `error` (naming the option and the bad value) on a bad command
// line. options.help is set for -h/--help.
bool parseOptions(int argc, char** argv, BenchOptions& options, std::string& error);

}  // namespace rbbench
