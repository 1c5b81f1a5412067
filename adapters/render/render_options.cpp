// Command-line parsing of raybridge-render.
#include "render_options.h"

#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <vector>

namespace rbRender {

namespace {

constexpr uint32_t kMaxSize = 16384;  // the engine's render-target limit
const float kDefaultReflectionRoughness = rbAdapter::FrameSettings{}.reflectionRoughnessThreshold;
const uint32_t kDefaultReflectionRays = rbAdapter::FrameSettings{}.reflectionRaysPerPixel;

std::string quoted(const std::string& s) { return "'" + s + "'"; }

bool parseFloat(const std::string& text, float& out) {
  if (text.empty()) return false;
  errno = 0;
  char* end = nullptr;
  out = std::strtof(text.c_str(), &end);
  return errno == 0 && end == text.c_str() + text.size() && std::isfinite(out);
}

// Seconds for --time / --fps: finite and not negative (or positive), the error names the value.
std::string parseSeconds(const std::string& option, const std::string& text, bool allowZero, double& out) {
  errno = 0;
  char* end = nullptr;
  const double v = text.empty() ? 0.0 : std::strtod(text.c_str(), &end);
  if (text.empty() || errno != 0 || end != text.c_str() + text.size())
    return option + ": " + quoted(text) + " is not a number";
  if (!std::isfinite(v)) return option + ": " + quoted(text) + " is not finite; give a finite number";
  if (v < 0.0 || (!allowZero && v == 0.0))
    return option + ": " + text + (allowZero ? " is negative; give 0 or more" : " must be greater than 0");
  out = v;
  return {};
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
         "1280x720, hybrid mode, preset high, into out/final.png and out/final.exr).\n"
         "  --scene FILE.gltf|.glb       scene to render (default: the engine's procedural demo scene)\n"
         "  --width W --height H         image size, 1..16384 (default 1280x720)\n"
         "  --camera ex,ey,ez,tx,ty,tz,fovy\n"
         "                               eye, target, vertical fov in degrees; up = +Y, right-handed, pixel (0,0)\n"
         "                               top-left, primary rays through pixel centres (default: the scene's camera,\n"
         "                               else framed on the scene bounds)\n"
         "  --sun dx,dy,dz               direction towards the sun (default: the scene's sun)\n"
         "  --preset NAME                effects and quality (default high):\n"
         "                                 low     hard shadows, AO 4 rays\n"
         "                                 medium  soft shadows 4 rays, AO 4 rays\n"
         "                                 high    medium + reflections\n"
         "                                 ultra   soft shadows 8 rays, AO 16 rays, reflections\n"
         "                                 shadows | ao | reflections   that effect alone (shadows: soft, 4 rays)\n"
         "                               explicit options below override what the preset sets\n"
         "  --effects LIST               effects to run, comma-separated from shadows,ao,reflections, or none\n"
         "                               (overrides the preset's set, keeps its quality settings)\n"
         "  --sun-radius DEG             angular radius of the sun, 0 = hard shadows (default: 0.5 for presets\n"
         "                               with soft shadows, else 0)\n"
         "  --shadow-rays N              rays per pixel for soft shadows, 1..4096 (default: the preset's)\n"
         "  --ao-rays N                  AO rays per pixel, 1..4096 (default: the preset's, else 4); 0 is an error\n"
         "  --ao-range R                 AO ray length in world units, > 0 (default 1)\n"
         "  --ao-estimator binary|distance\n"
         "                               AO hits count as occluded, or t/range open (default binary)\n"
         "  --reflection-roughness T     roughness threshold in (0, 1]: rougher surfaces trace no reflection ray\n"
         "                               (default 0.5)\n"
         "  --reflection-rays N          reflection rays per glossy pixel, 1..64 (default 4)\n"
         "  --no-denoise                 use the raw soft-shadow and AO images (default: denoised)\n"
         "  --mode raster|hybrid         hybrid: Raybridge's effects; raster: the engine's counterparts of the\n"
         "                               same effects (shadow map, SSAO, reflection probe) (default hybrid)\n"
         "  --gbuffer-normals shading|geometric\n"
         "                               normal the passes use (default shading)\n"
         "  --out DIR                    output folder (default out): final.png, final.exr\n"
         "  --dump                       also depth.exr (distance from the eye, 0 = sky), normal.exr (world normal\n"
         "                               used by the passes), shadow.exr (sun visibility the lighting used; plus\n"
         "                               shadow_raw.exr when denoised), ao.exr (AO the lighting used; plus\n"
         "                               ao_raw.exr in hybrid mode), reflection.exr (hybrid), stats.json\n"
         "  --frames N                   frames to render, the last is reported (default 3)\n"
         "  --time T                     seconds into the animation the (last) frame shows, >= 0 (default 0)\n"
         "  --fps F                      frame k of --frames N shows T - (N-1-k)/F, so the frames animate into\n"
         "                               the last one (default: every frame at T)\n"
         "  --animation N|NAME           the animation that plays, by index or name (default: the first)\n"
         "  --characters N               the demo scene with N skinned characters (CesiumMan, Fox, BrainStem in\n"
         "                               turn, 1..1000), each playing its first animation at its own offset\n"
         "  --characters-from DIR        where their glTF folders are (default ../shared/scenes)\n"
         "  --dynamic-builds in-frame|async|async-late\n"
         "                               where deforming meshes' BLAS refits and rebuilds run: in the frame's\n"
         "                               command buffer, on the engine's async compute queue with this frame's\n"
         "                               TLAS waiting for them, or one frame late (the TLAS uses the previous\n"
         "                               pose; the graphics queue never waits). Without a second queue the async\n"
         "                               modes run in the frame, with the same result (default in-frame)\n"
         "  --device SUBSTR              pick the Vulkan device whose name contains SUBSTR\n"
         "  --validation                 enable VK_LAYER_KHRONOS_validation (also RAYBRIDGE_VALIDATION=1); exit\n"
         "                               status 3 if it reported errors\n";
}

ResolvedEffects resolve(const RenderOptions& o) {
  const rbAdapter::PresetDesc p = rbAdapter::presetDesc(o.preset);
  ResolvedEffects r;
  r.effects = o.effects ? *o.effects : p.effects;
  r.sunRadiusDegrees = o.sunRadiusDegrees ? *o.sunRadiusDegrees
                       : p.softShadows    ? rbAdapter::kDefaultSoftSunRadiusDegrees
                                          : 0.0f;
  // A preset without shadows (--effects adds them): soft shadows get Medium's 4 rays.
  const uint32_t presetShadowRays = (p.effects & rbAdapter::kEffectShadows) && p.softShadows ? p.shadowRaysPerPixel : 4;
  r.shadowRays = r.sunRadiusDegrees > 0.0f ? (o.shadowRays ? *o.shadowRays : presetShadowRays) : 1;
  r.aoRays = o.aoRays ? *o.aoRays : p.aoRaysPerPixel ? p.aoRaysPerPixel : 4;
  r.aoRange = o.aoRange ? *o.aoRange : 1.0f;
  r.reflectionRoughness = o.reflectionRoughness ? *o.reflectionRoughness : kDefaultReflectionRoughness;
  r.reflectionRays = o.reflectionRays ? *o.reflectionRays : kDefaultReflectionRays;
  return r;
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
    } else if (a == "--no-denoise") {
      o.denoise = false;
    } else if (a == "--scene" || a == "--out" || a == "--device" || a == "--width" || a == "--height" ||
               a == "--camera" || a == "--sun" || a == "--sun-radius" || a == "--shadow-rays" || a == "--mode" ||
               a == "--gbuffer-normals" || a == "--frames" || a == "--preset" || a == "--effects" ||
               a == "--ao-rays" || a == "--ao-range" || a == "--ao-estimator" || a == "--reflection-roughness" ||
               a == "--reflection-rays" || a == "--time" || a == "--fps" || a == "--animation" ||
               a == "--dynamic-builds" || a == "--characters" || a == "--characters-from") {
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
      } else if (a == "--time") {
        e = parseSeconds(a, value, true, o.time);
      } else if (a == "--fps") {
        double f = 0.0;
        if ((e = parseSeconds(a, value, false, f)).empty()) o.fps = f;
      } else if (a == "--animation") {
        if (value.empty()) e = "--animation: the index or name is empty";
        o.animation = value;
      } else if (a == "--characters") {
        e = parseUint(a, value, 1, 1000, o.characters);
      } else if (a == "--characters-from") {
        if (value.empty()) e = "--characters-from: the folder name is empty";
        o.charactersFrom = value;
      } else if (a == "--dynamic-builds") {
        if (value == "in-frame") o.dynamicMode = rb::DynamicBuildMode::InFrame;
        else if (value == "async") o.dynamicMode = rb::DynamicBuildMode::AsyncSameFrame;
        else if (value == "async-late") o.dynamicMode = rb::DynamicBuildMode::AsyncOneFrameLate;
        else e = "--dynamic-builds: " + quoted(value) + " is not in-frame, async or async-late";
      } else if (a == "--shadow-rays") {
        uint32_t n = 0;
        if ((e = parseUint(a, value, 1, 4096, n)).empty()) o.shadowRays = n;
      } else if (a == "--ao-rays") {
        uint32_t n = 0;
        if ((e = parseUint(a, value, 1, 4096, n)).empty()) o.aoRays = n;
      } else if (a == "--ao-range") {
        float r = 0.0f;
        if (!parseFloat(value, r)) e = "--ao-range: " + quoted(value) + " is not a number";
        else if (!(r > 0.0f)) e = "--ao-range: " + value + " must be greater than 0 (world units)";
        else o.aoRange = r;
      } else if (a == "--ao-estimator") {
        if (value == "binary") o.aoEstimator = rb::AoEstimator::Binary;
        else if (value == "distance") o.aoEstimator = rb::AoEstimator::DistanceWeighted;
        else e = "--ao-estimator: " + quoted(value) + " is not binary or distance";
      } else if (a == "--reflection-roughness") {
        float t = 0.0f;
        if (!parseFloat(value, t)) e = "--reflection-roughness: " + quoted(value) + " is not a number";
        else if (!(t > 0.0f && t <= 1.0f)) e = "--reflection-roughness: " + value + " is outside (0, 1]";
        else o.reflectionRoughness = t;
      } else if (a == "--reflection-rays") {
        uint32_t n = 0;
        if ((e = parseUint(a, value, 1, 64, n)).empty()) o.reflectionRays = n;
      } else if (a == "--preset") {
        if (auto p = rbAdapter::parsePreset(value)) o.preset = *p;
        else e = "--preset: " + quoted(value) + " is not low, medium, high, ultra, shadows, ao or reflections";
      } else if (a == "--effects") {
        rbAdapter::EffectSet set = 0;
        if (value != "none") {
          if (value.empty()) e = "--effects: the list is empty (use none for no effect)";
          else if (std::string pe = rbAdapter::parseEffects(value, set); !pe.empty()) e = "--effects: " + pe;
        }
        if (e.empty()) o.effects = set;
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
        float r = 0.0f;
        if (!parseFloat(value, r)) e = "--sun-radius: " + quoted(value) + " is not a number";
        else if (!(r >= 0.0f && r < 45.0f)) e = "--sun-radius: " + value + " is outside [0, 45) degrees";
        else o.sunRadiusDegrees = r;
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
  if (o.characters && !o.scene.empty())
    return "--characters: adds characters to the demo scene; it cannot be combined with --scene";
  if (!o.charactersFrom.empty() && !o.characters) return "--characters-from needs --characters N";
  if (uint64_t(o.width) * o.height > uint64_t(8192) * 8192)
    return "--width/--height: " + std::to_string(o.width) + "x" + std::to_string(o.height) +
           " exceeds 67 megapixels";
  return {};
}

}  // namespace rbRender
