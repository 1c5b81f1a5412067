// Command-line parsing of raybridge-render.
#include "render_options.h"

#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <vector>

namespace rbRender {

namespace {

constexpr uint32_t kMaxSize = 16384;  // the engine's render-target limit

std::string quoted(const std::string& s) { return "'" + s + "'"; }

bool parseFloat(const std::string& text, float& out) {
  if (text.empty()) return false;
  errno = 0;
  char* end = nullptr;
  out = std::strtof(text.c_str(), &end);
  return errno == 0 && end == text.c_str() + text.size() && std::isfinite(out);
}

std::string parseUint(const std::string& option, const std::string& text, uint32_t min, uint32_t max, uint32_t& out) {
  if (text.empty() || text.find_first_not_of("0123456789") != std::string::npos || text.size() > 9)
    return option + ": " + quoted(text) + " is not a whole number in " + std::to_string(min) + ".." + std::to_string(max);
  const unsigned long v = std::strtoul(text.c_str(), nullptr, 10);
  if (v < min || v > max)
    return option + ": " + text + " is outside " + std::to_string(min) + ".." + std::to_string(max);
  out = uint32_t(v);
  return {};
}

std::string parseList(const std::string& option, const std::string& text, size_t count, std::vector<float>& out) {
  out.clear();
  size_t start = 0;
  while (start <= text.size()) {
    size_t comma = text.find(',', start);
    const std::string item = text.substr(start, comma == std::string::npos ? std::string::npos : comma - start);
    float v;
    if (!parseFloat(item, v)) return option + ": " + quoted(item) + " in " + quoted(text) + " is not a number";
    out.push_back(v);
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
  if (out.size() != count)
    return option + ": expected " + std::to_string(count) + " comma-separated numbers, got " +
           std::to_string(out.size()) + " in " + quoted(text);
  return {};
}

}  // namespace

const char* renderUsage() {
  return "usage: raybridge-render [options]\n"
         "Renders one image headless with the sample engine and Raybridge (default: the procedural demo scene,\n"
         "1280x720, hybrid mode, into out/final.png and out/final.exr).\n"
         "  --scene FILE.gltf|.glb       scene to render (default: the engine's procedural demo scene)\n"
         "  --width W --height H         image size, 1..16384 (default 1280x720)\n"
         "  --camera ex,ey,ez,tx,ty,tz,fovy\n"
         "                               eye, target, vertical fov in degrees; up = +Y, right-handed, pixel (0,0)\n"
         "                               top-left, primary rays through pixel centres (default: the scene's camera,\n"
         "                               else framed on the scene bounds)\n"
         "  --sun dx,dy,dz               direction towards the sun (default: the scene's sun)\n"
         "  --sun-radius DEG             angular radius of the sun, 0 = hard shadows (default 0)\n"
         "  --shadow-rays N              rays per pixel for soft shadows, 1..4096 (default 8)\n"
         "  --mode raster|hybrid         engine shadow maps, or Raybridge ray-traced shadows (default hybrid)\n"
         "  --gbuffer-normals shading|geometric\n"
         "                               normal the passes use (default shading)\n"
         "  --out DIR                    output folder (default out): final.png, final.exr\n"
         "  --dump                       also depth.exr (distance from the eye, 0 = sky), normal.exr (world normal\n"
         "                               used by the passes), shadow.exr (sun visibility; hybrid mode only),\n"
         "                               stats.json\n"
         "  --frames N                   frames to render, the last is reported (default 3)\n"
         "  --device SUBSTR              pick the Vulkan device whose name contains SUBSTR\n"
         "  --validation                 enable VK_LAYER_KHRONOS_validation (also RAYBRIDGE_VALIDATION=1); exit\n"
         "                               status 3 if it reported errors\n";
}

std::string parseRenderOptions(int argc, char** argv, RenderOptions& o) {
  std::vector<float> list;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    std::string value;
    auto takeValue = [&]() -> bool {
      if (i + 1 >= argc) return false;
      value = argv[++i];
      return true;
    };
    auto needsValue = [&] { return a + " needs a value"; };
    std::string e;
    if (a == "--help" || a == "-h") {
      o.help = true;
    } else if (a == "--dump") {
      o.dump = true;
    } else if (a == "--validation") {
      o.validation = true;
    } else if (a == "--scene" || a == "--out" || a == "--device" || a == "--width" || a == "--height" ||
               a == "--camera" || a == "--sun" || a == "--sun-radius" || a == "--shadow-rays" || a == "--mode" ||
               a == "--gbuffer-normals" || a == "--frames") {
      if (!takeValue()) return needsValue();
      if (a == "--scene") {
        if (value.empty()) return "--scene: the file name is empty";
        o.scene = value;
      } else if (a == "--out") {
        if (value.empty()) return "--out: the folder name is empty";
        o.out = value;
      } else if (a == "--device") {
        o.device = value;
      } else if (a == "--width") {
        e = parseUint(a, value, 1, kMaxSize, o.width);
      } else if (a == "--height") {
        e = parseUint(a, value, 1, kMaxSize, o.height);
      } else if (a == "--frames") {
        e = parseUint(a, value, 1, 100000, o.frames);
      } else if (a == "--shadow-rays") {
        e = parseUint(a, value, 1, 4096, o.shadowRays);
      } else if (a == "--camera") {
        if ((e = parseList(a, value, 7, list)).empty()) {
          o.eye = glm::vec3(list[0], list[1], list[2]);
          o.target = glm::vec3(list[3], list[4], list[5]);
          o.fovYDegrees = list[6];
          if (*o.eye == *o.target) e = "--camera: eye equals target (" + value + "); the view direction is undefined";
          else if (!(o.fovYDegrees > 0.0f && o.fovYDegrees < 180.0f))
            e = "--camera: fovy " + std::to_string(o.fovYDegrees) + " is outside (0, 180) degrees";
        }
      } else if (a == "--sun") {
        if ((e = parseList(a, value, 3, list)).empty()) {
          o.sun = glm::vec3(list[0], list[1], list[2]);
          if (glm::length(*o.sun) < 1e-6f) e = "--sun: the direction " + value + " has zero length";
        }
      } else if (a == "--sun-radius") {
        if (!parseFloat(value, o.sunRadiusDegrees)) e = "--sun-radius: " + quoted(value) + " is not a number";
        else if (!(o.sunRadiusDegrees >= 0.0f && o.sunRadiusDegrees < 45.0f))
          e = "--sun-radius: " + value + " is outside [0, 45) degrees";
      } else if (a == "--mode") {
        if (value == "raster") o.mode = Mode::Raster;
        else if (value == "hybrid") o.mode = Mode::Hybrid;
        else e = "--mode: " + quoted(value) + " is not raster or hybrid";
      } else if (a == "--gbuffer-normals") {
        if (value == "shading") o.geometricNormals = false;
        else if (value == "geometric") o.geometricNormals = true;
        else e = "--gbuffer-normals: " + quoted(value) + " is not shading or geometric";
      }
    } else {
      return "unknown option " + quoted(a);
    }
    if (!e.empty()) return e;
  }
  if (uint64_t(o.width) * o.height > uint64_t(8192) * 8192)
    return "--width/--height: " + std::to_string(o.width) + "x" + std::to_string(o.height) +
           " exceeds 67 megapixels";
  return {};
}

}  // namespace rbRender
