// Command-line parsing of raybridge-render, through CLI11 (samples/common/cli_support.h).
#include "render_options.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <optional>
#include <vector>

#include "cli_support.h"
#include "reset_follow_up.h"

namespace rbRender {

namespace {

constexpr uint32_t kMaxSize = 16384;  // the engine's render-target limit

const std::vector<std::string> kEffectNames = {"shadows", "ao", "reflections", "lights"};  // bit i = name i
static_assert(rb::kEffectShadows == 1 && rb::kEffectAo == 2 && rb::kEffectReflections == 4 &&
              rb::kEffectLocalLights == 8);

// One line per preset, from the SDK's table: what it traces and what raster mode draws instead.
std::string presetTable() {
  std::string s;
  for (uint32_t i = 0; i < rb::kPresetCount; ++i) {
    const rb::Preset preset = rb::Preset(i);
    const rb::PresetDesc d = rb::presetDesc(preset);
    std::string line = std::string("\n  ") + rb::toString(preset);
    line.resize(18, ' ');
    std::vector<std::string> parts;
    if (d.effects & rb::kEffectShadows)
      parts.push_back(d.shadowRaysPerPixel > 1 ? "soft shadows " + std::to_string(d.shadowRaysPerPixel) + " rays" +
                                                     (d.shadowConvergedTiles ? ", converged tiles skipped" : "")
                                               : std::string("hard shadows"));
    if (d.effects & rb::kEffectAo)
      parts.push_back("AO " + std::to_string(d.aoRaysPerPixel) + " rays" + (d.aoHalfResolution ? " at half res" : ""));
    if (d.effects & rb::kEffectReflections) parts.push_back("reflections");
    line += parts.empty() ? std::string("no effect") : rbCli::joinNames(parts, ", ");
    if (d.raster.mapSize)
      line += "; raster: shadow map " + std::to_string(d.raster.mapSize) +
              (d.raster.pcfKernel ? ", PCF " + std::to_string(d.raster.pcfKernel) : std::string());
    s += line;
  }
  return s;
}

CLI::Validator effectSetValidator() {
  return CLI::Validator(
      [](std::string& value) {
        rb::EffectSet set = 0;
        return parseEffectSet(value, set);
      },
      "");
}

CLI::Validator halfResolutionValidator() {
  return CLI::Validator(
      [](std::string& value) {
        bool ao = false, reflections = false;
        return parseHalfResolution(value, ao, reflections);
      },
      "");
}

CLI::Validator presetValidator() {
  return CLI::Validator(
      [](std::string& value) {
        return rb::parsePreset(value) ? std::string()
                                      : rbCli::quote(value) + " is not a preset (" + rb::presetNames() + ")";
      },
      "");
}

// Every option of the command, stored into `o` when the parse runs its callbacks.
// --adaptive: "ao", "shadows=0.8", "ao=1.0,shadows", and a granularity for both: "ao,pixel", "ao,tile=8x4".
// Fills `o` when given; returns an error message or "".
std::string parseAdaptive(const std::string& value, RenderOptions* o) {
  std::optional<float> shadows, ao;
  rb::AdaptiveRayGranularity granularity = rb::AdaptiveRayGranularity::Tile;
  uint32_t tileWidth = 0, tileHeight = 0;
  // A tile side: a power of two from 1 to rb::kMaxAdaptiveTileSize.
  auto side = [](const std::string& text, uint32_t& out) {
    if (text.empty() || text.size() > 2 || text.find_first_not_of("0123456789") != std::string::npos) return false;
    out = uint32_t(std::stoul(text));
    return out >= 1 && out <= rb::kMaxAdaptiveTileSize && (out & (out - 1)) == 0;
  };
  size_t start = 0;
  while (start <= value.size()) {
    const size_t end = std::min(value.find(',', start), value.size());
    const std::string item = value.substr(start, end - start);
    const size_t eq = item.find('=');
    const std::string name = item.substr(0, eq);
    if (name == "pixel" || name == "tile") {
      granularity = name == "pixel" ? rb::AdaptiveRayGranularity::Pixel : rb::AdaptiveRayGranularity::Tile;
      tileWidth = tileHeight = 0;
      if (eq != std::string::npos) {
        const std::string shape = item.substr(eq + 1);
        const size_t x = shape.find('x');
        if (name == "pixel" || x == std::string::npos || !side(shape.substr(0, x), tileWidth) ||
            !side(shape.substr(x + 1), tileHeight)) {
          return "'" + shape + "' in '" + item + "' is not " +
                 (name == "pixel" ? std::string("allowed (pixel takes no size)")
                                  : "a tile WxH with sides 1, 2, 4 or 8 (e.g. tile=8x4)");
        }
      }
      start = end + 1;
      continue;
    }
    float ms = 0.0f;
    if (eq != std::string::npos) {
      const std::string number = item.substr(eq + 1);
      char* stop = nullptr;
      ms = std::strtof(number.c_str(), &stop);
      if (number.empty() || *stop != '\0' || !std::isfinite(ms) || ms <= 0.0f) {
        return "'" + number + "' in '" + item + "' is not a time in ms greater than 0";
      }
    }
    if (name == "shadows") {
      shadows = ms;
    } else if (name == "ao") {
      ao = ms;
    } else {
      return "'" + name + "' in '" + value +
             "' is not an effect with adaptive rays (shadows, ao) or a granularity "
             "(pixel, tile, tile=WxH)";
    }
    start = end + 1;
  }
  if (!shadows && !ao) return "'" + value + "' names no effect with adaptive rays (shadows, ao)";
  if (o) {
    o->adaptiveShadowsMs = shadows;
    o->adaptiveAoMs = ao;
    o->adaptiveGranularity = granularity;
    o->adaptiveTileWidth = tileWidth;
    o->adaptiveTileHeight = tileHeight;
  }
  return {};
}

// --camera's eye, target and fov (v, parsed from `text`): "" or what is wrong, naming the value and the valid range.
std::string checkCamera(const std::vector<float>& v, const std::string& text) {
  std::vector<std::string> items;  // the numbers as given, for the messages
  for (size_t start = 0, comma = 0; comma != std::string::npos; start = comma + 1) {
    comma = text.find(',', start);
    items.push_back(text.substr(start, comma == std::string::npos ? std::string::npos : comma - start));
  }
  static const char* const names[6] = {"ex", "ey", "ez", "tx", "ty", "tz"};
  for (size_t i = 0; i < 6; ++i)
    if (std::string e = checkCameraCoordinate(v[i], std::string(names[i]) + " " + items[i]); !e.empty())
      return e + " in '" + text + "'";
  const glm::dvec3 eye(v[0], v[1], v[2]), target(v[3], v[4], v[5]);
  if (eye == target) return "eye equals target (" + text + "); the view direction is undefined";
  const double apart = glm::length(target - eye), least = minEyeTargetDistance(eye, target);
  if (apart < least)
    return "eye and target are " + formatNumber(apart) + " apart in '" + text +
           "'; the view direction needs them at least " + formatNumber(least) + " apart";
  return checkFovY(v[6], "fovy " + items[6]);
}

// Every value of --camera is checked (a repeated option keeps the last, but a bad earlier one is still an error).
CLI::Validator cameraValidator() {
  return CLI::Validator(
      [](std::string& value) {
        std::vector<float> v;
        if (std::string e = rbCli::parseNumberList(value, 7, v); !e.empty()) return e;
        return checkCamera(v, value);
      },
      "");
}

// --sun's unit direction, or none for a zero vector. Scaled by the largest component before normalising: the squared
// length of 1e30,1e30,1e30 overflows a float, and that of 1e-30,0,0 underflows to 0, though both are directions.
std::optional<glm::vec3> sunDirection(const std::vector<float>& v) {
  const glm::vec3 d(v[0], v[1], v[2]);
  const float largest = std::max({std::abs(d.x), std::abs(d.y), std::abs(d.z)});
  if (largest == 0.0f) return std::nullopt;
  return glm::normalize(d / largest);
}

// The help text's frame, then what is rendered from where: the scene, the image size, the camera and the sun.
void addSceneAndCameraOptions(CLI::App& app, RenderOptions& o) {
  rbCli::prepare(app);
  app.description(
      "Renders one image headless with the sample engine and Raybridge (default: the procedural demo scene,\n"
      "1280x720, hybrid mode, preset high, into out/final.png and out/final.exr).");
  app.footer("Presets (--preset): the effects and their quality; explicit options override what the preset sets."
             "\n  ('shadows' is the earlier name of soft-shadows.)" +
             presetTable());

  app.add_option("--scene", o.scene, "scene to render (default: the engine's procedural demo scene)")
      ->type_name("FILE.gltf|.glb")
      ->check(rbCli::nonEmpty("file name"));
  app.add_option("--width", o.width, "image width (default 1280)")
      ->type_name("W")
      ->check(rbCli::wholeNumber(1, kMaxSize));
  app.add_option("--height", o.height, "image height (default 720)")
      ->type_name("H")
      ->check(rbCli::wholeNumber(1, kMaxSize));
  app.add_option_function<std::string>(
         "--camera",
         [&o](const std::string& value) {
           std::vector<float> v;
           rbCli::parseNumberList(value, 7, v);  // validated by the check below
           o.eye = glm::vec3(v[0], v[1], v[2]);
           o.target = glm::vec3(v[3], v[4], v[5]);
           o.fovYDegrees = v[6];
         },
         "eye, target, vertical fov in degrees; up = +Y, right-handed, pixel (0,0) top-left,\n"
         "primary rays through pixel centres; coordinates within +-1e9, fov in [0.01, 180)\n"
         "(default: the scene's camera, else framed on the scene bounds)")
      ->type_name("ex,ey,ez,tx,ty,tz,fovy")
      ->check(cameraValidator());
  app.add_option("--camera-path", o.cameraPath,
                 "camera keyframes (JSON: position, orientation quaternion, duration; see\n"
                 "samples/common/camera_path.h); frame k of --frames N is at k/(N-1) of the path,\n"
                 "or at k/F seconds with --fps F; the last frame is captured (not with --camera)")
      ->type_name("FILE.json")
      ->check(rbCli::nonEmpty("file name"));
  app.add_option_function<std::string>(
         "--sun",
         [&o](const std::string& value) {
           std::vector<float> v;
           rbCli::parseNumberList(value, 3, v);  // validated by the check below
           o.sun = sunDirection(v);
         },
         "direction towards the sun (default: the scene's sun)")
      ->type_name("dx,dy,dz")
      ->check(CLI::Validator(
          [](std::string& value) {
            std::vector<float> v;
            if (std::string e = rbCli::parseNumberList(value, 3, v); !e.empty()) return e;
            if (sunDirection(v)) return std::string();
            return "the direction " + value + " has zero length; give a direction towards the sun, e.g. 0.3,1,0.2";
          },
          ""));
}

// The effects: the preset and the options that override its set and its quality, the TLAS builds, raster mode's
// shadow map.
void addEffectOptions(CLI::App& app, RenderOptions& o) {
  app.add_option_function<std::string>(
         "--preset", [&o](const std::string& value) { o.preset = *rb::parsePreset(value); },
         "effects and quality, one of the presets below (default high)")
      ->type_name("NAME")
      ->check(presetValidator());
  app.add_option_function<std::string>(
         "--effects",
         [&o](const std::string& value) {
           rb::EffectSet set = 0;
           parseEffectSet(value, set);
           o.effects = set;
         },
         "effects to run, comma-separated from shadows,ao,reflections,lights, or none\n"
         "(overrides the preset's set, keeps its quality settings; default: the preset's,\n"
         "plus lights when the scene has KHR_lights_punctual lights, except with preset none)")
      ->type_name("LIST")
      ->check(effectSetValidator());
  app.add_option_function<float>(
         "--sun-radius", [&o](const float& v) { o.sunRadiusDegrees = v; },
         "angular radius of the sun, 0 = hard shadows (default: 0.5 when the shadows\n"
         "are soft)")
      ->type_name("DEG")
      ->check(rbCli::floatNumber(rbCli::atLeast(0.0), rbCli::below(45.0), " degrees"));
  app.add_option_function<uint32_t>(
         "--shadow-rays", [&o](const uint32_t& v) { o.shadowRays = v; },
         "rays per pixel for shadows, 1 = hard (default: the preset's, else 4)")
      ->type_name("N")
      ->check(rbCli::wholeNumber(1, 4096));
  app.add_option_function<uint32_t>(
         "--ao-rays", [&o](const uint32_t& v) { o.aoRays = v; }, "AO rays per pixel (default: the preset's, else 4)")
      ->type_name("N")
      ->check(rbCli::wholeNumber(1, 4096));
  app.add_option_function<float>(
         "--ao-range", [&o](const float& v) { o.aoRange = v; }, "AO ray length in world units (default 1)")
      ->type_name("R")
      ->check(rbCli::floatNumber(rbCli::above(0.0), rbCli::unbounded(), " (world units)"));
  rbCli::addEnum(app, "--ao-estimator", o.aoEstimator,
                 {{"binary", rb::AoEstimator::Binary}, {"distance", rb::AoEstimator::DistanceWeighted}},
                 "AO hits count as occluded, or t/range open (default binary)");
  app.add_option_function<float>(
         "--reflection-roughness", [&o](const float& v) { o.reflectionRoughness = v; },
         "roughness threshold: rougher surfaces trace no reflection ray (default 0.5)")
      ->type_name("T")
      ->check(rbCli::floatNumber(rbCli::above(0.0), rbCli::atMost(1.0)));
  app.add_option_function<uint32_t>(
         "--reflection-rays", [&o](const uint32_t& v) { o.reflectionRays = v; },
         "reflection rays per glossy pixel (default 4)")
      ->type_name("N")
      ->check(rbCli::wholeNumber(1, 64));
  app.add_option_function<uint32_t>(
         "--light-rays", [&o](const uint32_t& v) { o.lightRays = v; },
         "shadow rays per pixel shared by the scene's punctual lights, 0 = exact: one\n"
         "ray per light that reaches the pixel (default 4)")
      ->type_name("N")
      ->check(rbCli::zeroOrWholeNumber(1, 64, "exact"));
  app.add_option_function<std::string>(
         "--half-res",
         [&o](const std::string& value) {
           parseHalfResolution(value, o.halfResAo, o.halfResReflections);
           o.halfResGiven = true;
         },
         "effects traced at half resolution (one pixel per 2x2 block, rotating over 4\n"
         "frames) and upsampled by depth and normals, comma-separated from ao,reflections,\n"
         "or none (default: the preset's; every preset with AO traces it at half resolution)")
      ->type_name("LIST")
      ->check(halfResolutionValidator());
  app.add_flag_callback(
      "--no-denoise", [&o] { o.denoise = false; }, "use the raw shadow, AO and local-light images (default: denoised)");
  app.add_flag_callback(
      "--reorder", [&o] { o.invocationReorder = true; },
      "reflections with shader execution reordering where the device has\n"
      "VK_NV_ray_tracing_invocation_reorder (default: off; stats.json tells)");
  rbCli::addEnum(app, "--tlas-mode", o.tlasMode,
                 {{"adaptive", rb::TlasBuildMode::Adaptive},
                  {"rebuild", rb::TlasBuildMode::Rebuild},
                  {"refit", rb::TlasBuildMode::UpdateIfPossible}},
                 "how the TLAS is built each frame: adaptive (refit, rebuild when instances drift\n"
                 "apart or every 60 frames), rebuild (every frame) or refit (always when valid)\n"
                 "(default: adaptive)");
  app.add_option_function<uint32_t>(
         "--shadow-map-size", [&o](const uint32_t& v) { o.shadowMapSize = v; },
         "raster mode's shadow map, texels squared, 0 = none (default: the preset's)")
      ->type_name("N")
      ->check(rbCli::zeroOrWholeNumber(1024, 8192, "no shadow map"));
  app.add_option_function<uint32_t>(
         "--pcf", [&o](const uint32_t& v) { o.pcfKernel = v; },
         "raster mode's PCF kernel, taps per axis (default: the preset's)")
      ->type_name("N")
      ->check(rbCli::wholeNumber(1, 9));
}

// The mode, the outputs and the frames: how many, at which animation time, which animation or characters.
void addFrameOptions(CLI::App& app, RenderOptions& o) {
  rbCli::addEnum(app, "--mode", o.mode,
                 {{"raster", Mode::Raster}, {"hybrid", Mode::Hybrid}, {"raytraced", Mode::RayTraced}},
                 "hybrid: Raybridge's effects; raster: the engine's counterparts of the same\n"
                 "effects (shadow map, SSAO, reflection probe); raytraced: no raster shading,\n"
                 "one primary ray per pixel shaded by Raybridge (sun with a shadow ray, sky\n"
                 "ambient, emission, the punctual lights; no AO or reflections) (default hybrid)");
  rbCli::addEnum(app, "--gbuffer-normals", o.geometricNormals, {{"shading", false}, {"geometric", true}},
                 "normal the passes use (default shading)");
  app.add_option("--out", o.out, "output folder (default out): final.png, final.exr")
      ->type_name("DIR")
      ->check(rbCli::nonEmpty("folder name"));
  app.add_option("--compare-with", o.compareWith,
                 "with --dump: each effect image (shadow, ao, reflection, lights) against the one\n"
                 "an earlier --dump of the same size and camera wrote to DIR: RMSE into stats.json")
      ->type_name("DIR")
      ->check(CLI::ExistingDirectory);
  app.add_flag("--dump", o.dump,
               "also depth.exr (distance from the eye, 0 = sky), normal.exr (world normal used\n"
               "by the passes), shadow.exr (sun visibility the lighting used; plus shadow_raw.exr\n"
               "when denoised), ao.exr (AO the lighting used; plus ao_raw.exr in hybrid mode),\n"
               "reflection.exr (hybrid), lights.exr (shadowed irradiance E of the scene's punctual\n"
               "lights, no BRDF or albedo, no sun; plus lights_raw.exr when denoised; lights.png and\n"
               "lights_raw.png show them as E/(1+E)), stats.json; --mode raytraced: depth.exr\n"
               "(the primary rays' own distances) and stats.json");
  app.add_option("--frames", o.frames, "frames to render, the last is reported (default 3)")
      ->type_name("N")
      ->check(rbCli::wholeNumber(1, 100000));
  app.add_option("--time", o.time, "seconds into the animation the (last) frame shows (default 0)")
      ->type_name("T")
      ->check(rbCli::realNumber(rbCli::atLeast(0.0)));
  app.add_option_function<double>(
         "--fps", [&o](const double& v) { o.fps = v; },
         "frame k of --frames N shows T - (N-1-k)/F, so the frames animate into the\n"
         "last one (default: every frame at T)")
      ->type_name("F")
      ->check(rbCli::realNumber(rbCli::above(0.0)));
  app.add_option("--animation", o.animation, "the animation that plays, by index or name (default: the first)")
      ->type_name("N|NAME")
      ->check(rbCli::nonEmpty("index or name"));
  app.add_option("--characters", o.characters,
                 "the demo scene with N skinned characters (CesiumMan, Fox, BrainStem in turn),\n"
                 "each playing its first animation at its own offset")
      ->type_name("N")
      ->check(rbCli::wholeNumber(1, 1000));
}

// Where rays are spent: tile classification, converged tiles per effect, adaptive rays.
void addScheduleOptions(CLI::App& app, RenderOptions& o) {
  app.add_flag("--tile-classifier", o.tileClassifier,
               "hybrid shadows: classify 8x8 tiles and trace only those with a pixel that needs\n"
               "a ray (same image; off by default, see docs/performance.md)");
  app.add_option_function<uint32_t>(
         "--converged-tiles", [&o](const uint32_t& v) { o.convergedTiles = v; },
         "soft shadows: skip the 8x8 tiles whose denoised history has converged, each\n"
         "still traced once in K frames (turns the tile classifier on; e.g. 8, the default;\n"
         "the soft-shadow presets skip them at the default K without this option)")
      ->type_name("K")
      ->check(rbCli::wholeNumber(1, 65535));
  app.add_flag("--no-converged-tiles", o.noConvergedTiles,
               "soft shadows: trace every tile every frame (the soft-shadow presets skip converged\n"
               "tiles by default)");
  app.add_flag("--no-short-history-filter", o.noShortHistoryFilter,
               "AO: its denoiser filters pixels with a short history as any other\n"
               "(AoEffectSettings::disableShortHistoryFilter; to measure what the filter costs)");
  app.add_flag("--no-reset-rays", o.noResetRays,
               "soft shadows and AO: trace their own rays per pixel where a change restarts the\n"
               "history too (Shadow/AoEffectSettings::disableResetRays; to measure what reset rays buy)");
  app.add_flag("--no-reflection-changes", o.noReflectionChanges,
               "reflections: do not restart the history where a reflection ray hits the reach of a\n"
               "local light that changed (ReflectionEffectSettings::disableRelitResets)");
  app.add_option("--reset-rays", o.resetRays,
                 "soft shadows and AO: rays per pixel where a change restarts the history\n"
                 "(RaySchedule::resetRays; default: rb::kDefaultResetRaysFactor x their rays)")
      ->type_name("N")
      ->check(rbCli::wholeNumber(1, rb::kMaxRaysPerPixel));
  app.add_option("--reset-follow-up", o.resetFollowUp,
                 "soft shadows and AO: frames after a change that its pixels still trace the reset rays\n"
                 "(0 = none; HybridEffectsDesc::resetFollowUpFrames, default rb::kDefaultResetFollowUpFrames)")
      ->type_name("N")
      ->check(rbCli::wholeNumber(0, rb::kMaxResetFollowUpFrames));
  app.add_option_function<uint32_t>(
         "--converged-ao", [&o](const uint32_t& v) { o.convergedAo = v; },
         "AO: skip the 8x8 tiles whose denoised history has converged, each still traced\n"
         "once in K frames (AO at full resolution: --half-res reflections or none)")
      ->type_name("K")
      ->check(rbCli::wholeNumber(1, 65535));
  app.add_option_function<uint32_t>(
         "--converged-reflections", [&o](const uint32_t& v) { o.convergedReflections = v; },
         "reflections: skip the 8x8 tiles whose denoised history has converged and whose view\n"
         "has not turned, each still traced once in K frames (full resolution: --half-res ao or none)")
      ->type_name("K")
      ->check(rbCli::wholeNumber(1, 65535));
  app.add_option_function<uint32_t>(
         "--converged-lights", [&o](const uint32_t& v) { o.convergedLights = v; },
         "local lights: skip the 8x8 tiles whose denoised irradiance has converged, each still\n"
         "traced once in K frames (stochastic: --light-rays N > 0)")
      ->type_name("K")
      ->check(rbCli::wholeNumber(1, 65535));
  app.add_option_function<std::string>(
         "--adaptive", [&o](const std::string& v) { parseAdaptive(v, &o); },
         "adaptive rays per pixel for soft shadows and AO, planned from the denoiser's history:\n"
         "EFFECT[=MS],... with EFFECT shadows or ao and MS a GPU time target for its pass\n"
         "(default: the preset's rays, redistributed); e.g. ao=1.0,shadows. One count per\n"
         "8x8 tile by default (warp-uniform); add pixel for one per pixel, or tile=WxH\n"
         "(sides 1, 2, 4 or 8), e.g. ao,tile=8x4")
      ->type_name("LIST")
      ->check(CLI::Validator([](std::string& v) { return parseAdaptive(v, nullptr); }, ""));
  app.add_option("--budget", o.budgetMs,
                 "a GPU time in ms for everything Raybridge records in a frame, which the SDK holds by\n"
                 "dividing it between the effects (HybridEffectsDesc::budgetMs): adaptive rays for\n"
                 "soft shadows and AO, reflections at full or half resolution, local-light rays")
      ->type_name("MS")
      ->check(rbCli::floatNumber(rbCli::above(0.0), rbCli::atMost(double(rb::kMaxFrameBudgetMs)), " ms"));
  app.add_flag("--no-aliasing", o.noAliasing,
               "each denoiser keeps its own transient images instead of sharing one set\n"
               "(HybridEffectsDesc::disableTransientAliasing): more memory, the same images");
  app.add_flag("--no-sun-cache", o.noSunCache,
               "every reflection hit traces its sun shadow ray, none reads the shadow effect's image\n"
               "(ReflectionEffectSettings::disableSunFromScreen)");
}

// The performance scene and where the shared models are, the dynamic BLAS builds, the device and validation.
void addSceneSourceAndDeviceOptions(CLI::App& app, RenderOptions& o) {
  app.add_flag("--perf-scene", o.perfScene,
               "the performance scene instead of the demo: the shared static glTF models, each\n"
               "instanced on a ring around the centre, on a finely tessellated ground (about\n"
               "3M triangles in 400 instances; docs/performance.md)");
  app.add_flag("--glossy-scene", o.glossyScene,
               "the glossy scene instead of the demo: a polished tiled floor under a grid of\n"
               "metal spheres, tori, boxes and columns, most of them at roughness 0.2-0.5 (about\n"
               "1.6M triangles in 82 instances, procedural; docs/performance.md)");
  app.add_option("--perf-ground", o.perfGroundSegments,
                 "--perf-scene's ground in N x N quads (default 768: 1.18M triangles)")
      ->type_name("N")
      ->check(rbCli::wholeNumber(1, 4096));
  app.add_option("--perf-copies", o.perfCopies,
                 "--perf-scene with K times as many copies of every model, on further rings\n"
                 "(default 1)")
      ->type_name("K")
      ->check(rbCli::wholeNumber(1, 256));
  app.add_flag("--perf-ground-only", o.perfGroundOnly, "--perf-scene's ground alone, no model");
  app.add_option("--models-from,--characters-from", o.modelsFrom,
                 "where the glTF folders of --characters and --perf-scene are\n"
                 "(default ../shared/scenes)")
      ->type_name("DIR")
      ->check(rbCli::nonEmpty("folder name"));
  rbCli::addEnum(app, "--dynamic-builds", o.dynamicMode,
                 {{"in-frame", rb::DynamicBuildMode::InFrame},
                  {"async", rb::DynamicBuildMode::AsyncSameFrame},
                  {"async-late", rb::DynamicBuildMode::AsyncOneFrameLate}},
                 "where deforming meshes' BLAS refits and rebuilds run: in the frame's command\n"
                 "buffer, on the engine's async compute queue with this frame's TLAS waiting for\n"
                 "them, or one frame late (the TLAS uses the previous pose; the graphics queue\n"
                 "never waits). Without a second queue the async modes run in the frame, with the\n"
                 "same result (default in-frame)");
  app.add_option("--device", o.device, "pick the Vulkan device whose name contains SUBSTR")->type_name("SUBSTR");
  app.add_flag("--validation", o.validation,
               "enable VK_LAYER_KHRONOS_validation (also RAYBRIDGE_VALIDATION=1); exit status 3\n"
               "if it reported errors");
}

// The options in the order --help lists them.
void addOptions(CLI::App& app, RenderOptions& o) {
  addSceneAndCameraOptions(app, o);
  addEffectOptions(app, o);
  addFrameOptions(app, o);
  addScheduleOptions(app, o);
  addSceneSourceAndDeviceOptions(app, o);
}

}  // namespace

std::string parseEffectSet(std::string_view text, rb::EffectSet& out) {
  if (text == "none") {
    out = 0;
    return {};
  }
  return rbCli::parseNameSet(text, kEffectNames, "an effect", out);
}

std::string effectSetToString(rb::EffectSet effects) {
  std::vector<std::string> names;
  for (size_t i = 0; i < kEffectNames.size(); ++i)
    if (effects & (1u << i)) names.push_back(kEffectNames[i]);
  return rbCli::join(names, ",");
}

std::string formatNumber(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g", v);
  return buf;
}

std::string checkCameraCoordinate(double value, const std::string& what) {
  if (std::abs(value) <= kMaxCameraCoordinate) return {};
  return what + " is outside [-" + formatNumber(kMaxCameraCoordinate) + ", " + formatNumber(kMaxCameraCoordinate) +
         "] (world units)";
}

double minEyeTargetDistance(const glm::dvec3& eye, const glm::dvec3& target) {
  const double largest = std::max({1.0, std::abs(eye.x), std::abs(eye.y), std::abs(eye.z), std::abs(target.x),
                                   std::abs(target.y), std::abs(target.z)});
  return kMinEyeTargetDistance * largest;
}

std::string checkFovY(double degrees, const std::string& what) {
  if (degrees >= kMinFovYDegrees && degrees < kMaxFovYDegrees) return {};
  return what + " is outside [" + formatNumber(kMinFovYDegrees) + ", " + formatNumber(kMaxFovYDegrees) + ") degrees";
}

std::string parseHalfResolution(std::string_view text, bool& ao, bool& reflections) {
  if (text == "none") {
    ao = reflections = false;
    return {};
  }
  uint32_t set = 0;
  if (std::string e = rbCli::parseNameSet(text, {"ao", "reflections"}, "an effect with half-resolution tracing", set);
      !e.empty())
    return e;
  ao = set & 1u;
  reflections = set & 2u;
  return {};
}

const char* renderUsage() {
  static const std::string help = [] {
    RenderOptions unused;
    CLI::App app{"", "raybridge-render"};
    addOptions(app, unused);
    return app.help();
  }();
  return help.c_str();
}

ResolvedEffects resolve(const RenderOptions& o) {
  const rb::PresetDesc p = rb::presetDesc(o.preset);
  ResolvedEffects r;
  rb::HybridEffectsDesc& h = r.hybrid;
  h.effects = o.effects ? *o.effects : p.effects;

  // Shadows: explicit rays, else the preset's (1 = hard), else 4 where --effects added shadows to a preset
  // without them. --sun-radius 0 forces hard shadows; a radius > 0 makes a hard preset soft (4 rays).
  const bool presetShadows = (p.effects & rb::kEffectShadows) && p.shadowRaysPerPixel > 0;
  uint32_t shadowRays = o.shadowRays    ? *o.shadowRays
                        : presetShadows ? p.shadowRaysPerPixel
                                        : rb::kDefaultSoftShadowRays;
  if (o.sunRadiusDegrees && *o.sunRadiusDegrees <= 0.0f) {
    shadowRays = 1;
  } else if (o.sunRadiusDegrees) {
    h.shadows.softAngularRadiusDegrees = *o.sunRadiusDegrees;
    if (!o.shadowRays && shadowRays == 1) shadowRays = rb::kDefaultSoftShadowRays;
  }
  h.shadows.raysPerPixel = shadowRays;
  h.shadows.disableDenoiser = !o.denoise;
  h.shadows.schedule.tileClassifier = o.tileClassifier;
  // The preset's converged tiles need the shadow denoiser's history: --no-denoise leaves them off.
  h.shadows.schedule.convergedTiles.enabled = o.convergedTiles.has_value() ||
                                              (p.shadowConvergedTiles && o.denoise && !o.noConvergedTiles);
  h.shadows.schedule.convergedTiles.refreshPeriod = o.convergedTiles.value_or(0);
  h.shadows.schedule.adaptive.enabled = o.adaptiveShadowsMs.has_value();
  h.shadows.schedule.adaptive.timeBudgetMs = o.adaptiveShadowsMs.value_or(0.0f);
  h.shadows.schedule.adaptive.granularity = o.adaptiveGranularity;
  h.shadows.schedule.adaptive.tileWidth = o.adaptiveTileWidth;
  h.shadows.schedule.adaptive.tileHeight = o.adaptiveTileHeight;
  if ((h.effects & rb::kEffectShadows) && shadowRays > 1)
    r.sunRadiusDegrees = h.shadows.softAngularRadiusDegrees > 0.0f ? h.shadows.softAngularRadiusDegrees
                                                                   : rb::kDefaultSoftLightAngularRadiusDegrees;

  h.ao.raysPerPixel = o.aoRays ? *o.aoRays : p.aoRaysPerPixel ? p.aoRaysPerPixel : rb::kDefaultAoRays;
  h.ao.range = o.aoRange ? *o.aoRange : rb::kDefaultAoRange;
  h.ao.estimator = o.aoEstimator;
  h.ao.disableDenoiser = !o.denoise;
  h.ao.disableShortHistoryFilter = o.noShortHistoryFilter;
  h.ao.disableResetRays = o.noResetRays;
  h.shadows.disableResetRays = o.noResetRays;
  rbTools::applyResetFollowUp(h, o.resetFollowUp);
  h.reflections.disableRelitResets = o.noReflectionChanges;
  h.budgetMs = o.budgetMs.value_or(0.0f);
  h.disableTransientAliasing = o.noAliasing;
  h.reflections.disableSunFromScreen = o.noSunCache;
  h.ao.schedule.adaptive.enabled = o.adaptiveAoMs.has_value();
  h.ao.schedule.adaptive.timeBudgetMs = o.adaptiveAoMs.value_or(0.0f);
  h.ao.schedule.adaptive.granularity = o.adaptiveGranularity;
  h.ao.schedule.adaptive.tileWidth = o.adaptiveTileWidth;
  h.ao.schedule.adaptive.tileHeight = o.adaptiveTileHeight;
  h.ao.schedule.halfResolution = o.halfResGiven ? o.halfResAo : p.aoHalfResolution;
  h.ao.schedule.convergedTiles.enabled = o.convergedAo.has_value();
  h.ao.schedule.convergedTiles.refreshPeriod = o.convergedAo.value_or(0);

  const uint32_t lightRays = o.lightRays ? *o.lightRays : kDefaultLightRays;
  h.localLights.mode = lightRays ? rb::ManyLightMode::Stochastic : rb::ManyLightMode::Exact;
  h.localLights.raysPerPixel = lightRays;
  h.localLights.disableDenoiser = !o.denoise;
  h.localLights.schedule.convergedTiles.enabled = o.convergedLights.has_value();
  h.localLights.schedule.convergedTiles.refreshPeriod = o.convergedLights.value_or(0);

  h.reflections.roughnessThreshold = o.reflectionRoughness ? *o.reflectionRoughness : kDefaultReflectionRoughness;
  h.reflections.raysPerPixel = o.reflectionRays ? *o.reflectionRays : kDefaultReflectionRays;
  h.reflections.schedule.halfResolution = o.halfResReflections;
  // --reset-rays where the schedule traces every pixel its own count (not adaptive, not at half resolution).
  h.shadows.schedule.resetRays = h.shadows.schedule.adaptive.enabled ? 0u : o.resetRays;
  h.ao.schedule.resetRays = h.ao.schedule.adaptive.enabled || h.ao.schedule.halfResolution ? 0u : o.resetRays;
  h.reflections.schedule.convergedTiles.enabled = o.convergedReflections.has_value();
  h.reflections.schedule.convergedTiles.refreshPeriod = o.convergedReflections.value_or(0);
  h.reflections.invocationReorder = o.invocationReorder;
  h.tlasMode = o.tlasMode;

  r.raster = p.raster;
  if (o.shadowMapSize) r.raster.mapSize = *o.shadowMapSize;
  if (o.pcfKernel) r.raster.pcfKernel = *o.pcfKernel;
  return r;
}

std::string parseRenderOptions(int argc, char** argv, RenderOptions& o) {
  CLI::App app{"", "raybridge-render"};
  addOptions(app, o);
  if (std::string e = rbCli::parse(app, argc, argv, o.help); !e.empty() || o.help) return e;
  if (o.characters && !o.animation.empty())
    return "--animation: with --characters every character plays its own animation; drop --animation";
  if (!o.cameraPath.empty() && o.eye) return "--camera-path and --camera both set the camera; give only one of them";
  if (o.characters && !o.scene.empty())
    return "--characters: adds characters to the demo scene; it cannot be combined with --scene";
  if (o.perfScene && (o.characters || !o.scene.empty()))
    return "--perf-scene is a scene of its own; it cannot be combined with --scene or --characters";
  if (o.glossyScene && (o.perfScene || o.characters || !o.scene.empty()))
    return "--glossy-scene is a scene of its own; it cannot be combined with --perf-scene, --scene or --characters";
  if (!o.perfScene && (o.perfGroundSegments || o.perfCopies || o.perfGroundOnly))
    return "--perf-ground, --perf-copies and --perf-ground-only shape the performance scene: add --perf-scene";
  if (o.perfGroundOnly && o.perfCopies) return "--perf-copies: --perf-ground-only places no model to copy";
  if (!o.modelsFrom.empty() && !o.characters && !o.perfScene)
    return "--models-from needs --characters N or --perf-scene";
  if (o.mode == Mode::RayTraced && o.effects)
    return "--effects: --mode raytraced shades every primary ray with the sun (a shadow ray), the sky and the "
           "punctual lights; AO and reflections need the G-buffer it does not draw, so it takes no effect list";
  if (o.mode == Mode::RayTraced && o.geometricNormals)
    return "--gbuffer-normals: --mode raytraced draws no G-buffer; its hits shade with the mesh normals";
  if (o.convergedTiles && o.noConvergedTiles) return "--converged-tiles and --no-converged-tiles: give one of them";
  if (o.noShortHistoryFilter && !o.denoise)
    return "--no-short-history-filter: the filter is part of the AO denoiser, which --no-denoise turns off; give one "
           "of them";
  if (o.noShortHistoryFilter && o.mode != Mode::Hybrid)
    return "--no-short-history-filter: only --mode hybrid denoises the SDK's AO";
  if (o.resetRays && o.noResetRays) return "--reset-rays and --no-reset-rays: give one of them";
  if (o.resetFollowUp && o.noResetRays)
    return "--reset-follow-up: follow-ups trace the reset rays, which --no-reset-rays turns off; give one of them";
  if (o.noReflectionChanges && (!o.denoise || o.mode != Mode::Hybrid))
    return "--no-reflection-changes: only --mode hybrid's denoised reflections have a history to restart";
  if (o.noResetRays && !o.denoise)
    return "--no-reset-rays: reset rays restart a denoiser's history, which --no-denoise turns off; give one of them";
  if (o.noResetRays && o.mode != Mode::Hybrid)
    return "--no-reset-rays: only --mode hybrid traces the SDK's soft shadows and AO";
  if (o.convergedTiles && !o.denoise)
    return "--converged-tiles: converged tiles are read from the shadow denoiser's history; drop --no-denoise";
  if (o.convergedTiles && o.mode != Mode::Hybrid)
    return "--converged-tiles: only --mode hybrid traces the shadow pass whose tiles it skips";
  if (o.convergedAo && !o.denoise)
    return "--converged-ao: converged tiles are read from the AO denoiser's history; drop --no-denoise";
  if (o.convergedAo && o.mode != Mode::Hybrid)
    return "--converged-ao: only --mode hybrid traces the AO pass whose tiles it skips";
  if (o.convergedAo && !(o.halfResGiven && !o.halfResAo))
    return "--converged-ao: it skips tiles of full-resolution AO, and every preset traces AO at half resolution: add "
           "--half-res reflections (or --half-res none)";
  if (o.convergedLights && !o.denoise)
    return "--converged-lights: converged tiles are read from the local-light denoiser's history; drop --no-denoise";
  if (o.convergedLights && o.mode != Mode::Hybrid)
    return "--converged-lights: only --mode hybrid traces the local-light pass whose tiles it skips";
  if (o.convergedLights && o.lightRays && *o.lightRays == 0)
    return "--converged-lights: --light-rays 0 traces every light exactly (no noise, no denoiser): give N > 0";
  if (o.convergedReflections && !o.denoise)
    return "--converged-reflections: converged tiles are read from the reflection denoiser's history; drop "
           "--no-denoise";
  if (o.convergedReflections && o.mode != Mode::Hybrid)
    return "--converged-reflections: only --mode hybrid traces the reflection pass whose tiles it skips";
  if (o.convergedReflections && o.halfResReflections)
    return "--converged-reflections: it skips tiles of full-resolution reflections: drop reflections from --half-res";
  if ((o.adaptiveShadowsMs || o.adaptiveAoMs) && !o.denoise)
    return "--adaptive: adaptive rays plan from the denoiser's history; drop --no-denoise";
  if ((o.adaptiveShadowsMs || o.adaptiveAoMs) && o.mode != Mode::Hybrid)
    return "--adaptive: only --mode hybrid traces the shadow and AO passes it adapts";
  if (!o.compareWith.empty() && !o.dump) return "--compare-with: it compares the images --dump writes; add --dump";
  if (o.budgetMs && (o.adaptiveShadowsMs || o.adaptiveAoMs))
    return "--budget: the frame budget sets the adaptive rays' time targets itself; drop --adaptive";
  if (o.budgetMs && o.mode != Mode::Hybrid)
    return "--budget: only --mode hybrid records the SDK's effects it divides the budget between";
  if (uint64_t(o.width) * o.height > uint64_t(8192) * 8192)
    return "--width/--height: " + std::to_string(o.width) + "x" + std::to_string(o.height) + " exceeds 67 megapixels";
  return {};
}

}  // namespace rbRender
