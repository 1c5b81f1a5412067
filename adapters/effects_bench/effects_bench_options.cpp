// Command-line parsing of raybridge-effects-bench (see the header).
#include "effects_bench_options.h"

#include <charconv>
#include <cstdlib>
#include <string_view>

namespace rbEffects {

namespace {

bool parseUint(std::string_view text, uint32_t& out) {
  const char* end = text.data() + text.size();
  auto [p, ec] = std::from_chars(text.data(), end, out);
  return ec == std::errc() && p == end;
}

bool parseFloat(const std::string& text, float& out) {
  char* end = nullptr;
  out = std::strtof(text.c_str(), &end);
  return !text.empty() && end == text.c_str() + text.size();
}

// "N" (every effect) or "shadows=N,ao=N,reflections=N" (any subset).
std::string parseReferenceRays(std::string_view text, Options& o) {
  uint32_t all = 0;
  if (parseUint(text, all)) {
    if (all == 0) return "--reference-rays: must be at least 1";
    o.referenceRaysShadows = o.referenceRaysAo = o.referenceRaysReflections = all;
    return {};
  }
  while (!text.empty()) {
    const size_t comma = text.find(',');
    const std::string_view item = text.substr(0, comma);
    text = comma == std::string_view::npos ? std::string_view() : text.substr(comma + 1);
    const size_t eq = item.find('=');
    uint32_t n = 0;
    if (eq == std::string_view::npos || !parseUint(item.substr(eq + 1), n) || n == 0)
      return "--reference-rays: bad item '" + std::string(item) + "' (want N or EFFECT=N,...)";
    const std::string_view name = item.substr(0, eq);
    if (name == "shadows") o.referenceRaysShadows = n;
    else if (name == "ao") o.referenceRaysAo = n;
    else if (name == "reflections") o.referenceRaysReflections = n;
    else return "--reference-rays: unknown effect '" + std::string(name) + "'";
  }
  return {};
}

}  // namespace

const char* usage() {
  return "usage: raybridge-effects-bench [--scenario speed-vs-error] [--effects shadows,ao,reflections]\n"
         "                               [--width W --height H] [--out FILE.json] [--images DIR]\n"
         "                               [--reference-rays N | shadows=N,ao=N,reflections=N]\n"
         "                               [--raw-rate-json BENCH.json] [--frames N] [--ao-range R]\n"
         "                               [--reflection-roughness T] [--quick] [--device SUBSTR] [--validation]\n"
         "For each effect: sweeps traced rays per pixel (raw and denoised) and the raster counterpart's\n"
         "resolution or kernel, times each setting with GPU timestamps (median of --frames frames) and measures\n"
         "its error (RMSE over surface pixels) against a converged reference traced by Raybridge.\n"
         "Defaults: 1920x1080 on a GPU, 320x180 on a CPU device; --quick: tiny size, few settings, and checks.\n";
}

std::string parseOptions(int argc, char** argv, Options& o) {
  for (int i = 0; i < argc; ++i) {
    if (i) o.commandLine.push_back(' ');
    o.commandLine.append(argv[i]);
  }
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    auto value = [&](std::string& out) -> bool {
      if (i + 1 >= argc) return false;
      out = argv[++i];
      return true;
    };
    std::string v;
    auto needValue = [&]() { return arg + ": missing value"; };
    auto uintArg = [&](std::optional<uint32_t>& out, uint32_t min) -> std::string {
      uint32_t n = 0;
      if (!value(v)) return needValue();
      if (!parseUint(v, n) || n < min) return arg + ": bad value '" + v + "'";
      out = n;
      return {};
    };
    std::string e;
    if (arg == "--help" || arg == "-h") o.help = true;
    else if (arg == "--quick") o.quick = true;
    else if (arg == "--validation") o.validation = true;
    else if (arg == "--scenario") {
      if (!value(o.scenario)) return needValue();
      if (o.scenario != "speed-vs-error") return "--scenario: unknown scenario '" + o.scenario + "' (only speed-vs-error)";
    } else if (arg == "--effects") {
      if (!value(v)) return needValue();
      if (std::string err = rbAdapter::parseEffects(v, o.effects); !err.empty()) return "--effects: " + err;
      if (o.effects == 0) return "--effects: no effect given";
    } else if (arg == "--width") e = uintArg(o.width, 16);
    else if (arg == "--height") e = uintArg(o.height, 16);
    else if (arg == "--frames") e = uintArg(o.timedFrames, 1);
    else if (arg == "--out") {
      if (!value(o.out)) return needValue();
    } else if (arg == "--images") {
      if (!value(o.images)) return needValue();
    } else if (arg == "--raw-rate-json") {
      if (!value(o.rawRateJson)) return needValue();
    } else if (arg == "--device") {
      if (!value(o.device)) return needValue();
    } else if (arg == "--reference-rays") {
      if (!value(v)) return needValue();
      e = parseReferenceRays(v, o);
    } else if (arg == "--ao-range") {
      if (!value(v)) return needValue();
      if (!parseFloat(v, o.aoRange) || !(o.aoRange > 0.0f)) return "--ao-range: bad value '" + v + "'";
    } else if (arg == "--reflection-roughness") {
      if (!value(v)) return needValue();
      if (!parseFloat(v, o.reflectionRoughness) || !(o.reflectionRoughness > 0.0f) || o.reflectionRoughness > 1.0f)
        return "--reflection-roughness: bad value '" + v + "' (want (0, 1])";
    } else {
      return "unknown option '" + arg + "'";
    }
    if (!e.empty()) return e;
  }
  if (o.width.has_value() != o.height.has_value()) return "--width and --height go together";
  return {};
}

}  // namespace rbEffects
