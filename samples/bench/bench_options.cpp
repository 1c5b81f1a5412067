#include "bench_options.h"

#include <algorithm>
#include <cstdlib>

namespace rbbench {

const std::vector<std::string>& scenarioNames() {
  static const std::vector<std::string> names = {"build", "duplication", "fastbuild-vs-fasttrace",
                                                 "compaction", "tlas", "trace", "gigarays"};
  return names;
}

std::string usage() {
  std::string s =
      "usage: raybridge-bench [--scenario NAME|all] [--out FILE.json] [--quick] [--full]\n"
      "                       [--width W --height H] [--device SUBSTR] [--scenes DIR]\n"
      "scenarios:";
  for (const std::string& n : scenarioNames()) s += " " + n;
  s +=
      "\n  --quick   smallest sizes, fewest repeats (smoke test)\n"
      "  --full    GPU sizes (1M triangles) even on a CPU device\n"
      "  --width/--height  trace resolution; default 1920x1080 on a GPU, 640x360 on a CPU device\n"
      "  --device  case-insensitive substring of the device name (else $RAYBRIDGE_DEVICE, else automatic)\n"
      "  --scenes  folder of glTF models, one per subfolder (default: ../shared/scenes beside the source tree)\n";
  return s;
}

namespace {

bool parseUint(const std::string& text, uint32_t& out) {
  if (text.empty() || !std::all_of(text.begin(), text.end(), [](char c) { return c >= '0' && c <= '9'; })) {
    return false;
  }
  unsigned long v = std::strtoul(text.c_str(), nullptr, 10);
  if (v == 0 || v > 16384) return false;
  out = static_cast<uint32_t>(v);
  return true;
}

}  // namespace

bool parseOptions(int argc, char** argv, BenchOptions& o, std::string& error) {
  o.scenesDir = std::string(RAYBRIDGE_SOURCE_DIR) + "/../shared/scenes";
  for (int i = 0; i < argc; ++i) {
    if (i) o.commandLine += ' ';
    o.commandLine += argv[i];
  }
  for (int i = 1; i < argc; ++i) {
    std::string a = argv[i];
    auto value = [&](std::string& out) {
      if (i + 1 >= argc) {
        error = a + " needs a value";
        return false;
      }
      out = argv[++i];
      return true;
    };
    std::string v;
    if (a == "--help" || a == "-h") {
      o.help = true;
    } else if (a == "--quick") {
      o.quick = true;
    } else if (a == "--full") {
      o.full = true;
    } else if (a == "--scenario") {
      if (!value(o.scenario)) return false;
      const auto& names = scenarioNames();
      if (o.scenario != "all" && std::find(names.begin(), names.end(), o.scenario) == names.end()) {
        error = "unknown scenario '" + o.scenario + "'";
        return false;
      }
    } else if (a == "--out") {
      if (!value(o.outPath)) return false;
    } else if (a == "--device") {
      if (!value(o.device)) return false;
    } else if (a == "--scenes") {
      if (!value(o.scenesDir)) return false;
    } else if (a == "--width" || a == "--height") {
      if (!value(v)) return false;
      if (!parseUint(v, a == "--width" ? o.width : o.height)) {
        error = a + " wants a whole number in 1..16384, got '" + v + "'";
        return false;
      }
    } else {
      error = "unknown argument '" + a + "'";
      return false;
    }
  }
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
