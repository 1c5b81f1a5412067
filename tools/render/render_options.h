// Command line of raybridge-render: parsing and validation (every error names the option and the bad value).
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

#include <glm/glm.hpp>

#include <raybridge/acceleration_structures.h>
#include <raybridge/ao_pass.h>
#include <raybridge/hybrid_effects.h>
#include <raybridge/presets.h>

namespace rbRender {

// Raster: the engine's own shadow maps, SSAO and probe. Hybrid: Raybridge's effects on the raster frame. RayTraced:
// no raster shading at all; Raybridge shades one primary ray per pixel (the thesis's pure ray-traced mode).
enum class Mode { Raster, Hybrid, RayTraced };

struct RenderOptions {
  std::string scene;  // empty = the engine's procedural demo scene
  uint32_t width = 1280, height = 720;
  // Eye, target, vertical fov in degrees, within the camera limits below; empty = the scene's own camera, else
  // framed on the scene bounds.
  std::optional<glm::vec3> eye, target;
  float fovYDegrees = 0.0f;
  // --camera-path FILE: the camera follows the JSON keyframes of samples/common/camera_path.h (not with --camera).
  // Frame k of `frames` is at path time k * total / max(frames - 1, 1), or k / fps with --fps (clamped to the
  // path's end); the captured frame is the last. Empty = no path.
  std::string cameraPath;
  std::optional<glm::vec3> sun;  // towards the sun, unit length; empty = the scene's sun, else the engine's default
  // Effects and their quality: the preset gives defaults, explicit options win (see resolve()).
  rb::Preset preset = rb::Preset::High;
  std::optional<rb::EffectSet> effects;   // --effects: overrides the preset's set
  std::optional<float> sunRadiusDegrees;  // --sun-radius; 0 = hard; else the SDK's 0.5 when shadows are soft
  std::optional<uint32_t> shadowRays;     // --shadow-rays; else the preset's (4 where it has no shadows)
  std::optional<uint32_t> aoRays;         // --ao-rays; else the preset's (4 where it has no AO)
  std::optional<float> aoRange;           // --ao-range; else the SDK's 1.0
  rb::AoEstimator aoEstimator = rb::AoEstimator::Binary;  // --ao-estimator binary|distance
  std::optional<float> reflectionRoughness;               // --reflection-roughness threshold; else the default below
  std::optional<uint32_t> reflectionRays;                 // --reflection-rays; else the default below
  // --light-rays: shadow rays per pixel shared by the scene's KHR_lights_punctual lights; 0 = exact (one ray per
  // light that reaches the pixel). Else kDefaultLightRays below.
  std::optional<uint32_t> lightRays;
  // --half-res ao,reflections (any subset, or none): the effects traced at half resolution with the depth-aware
  // upsample (HybridEffectsDesc::ao/reflections.schedule.halfResolution). Unset: the preset's (AO at half resolution in
  // every preset with AO, presets.h); `--half-res none` traces both at full resolution.
  bool halfResGiven = false;
  bool halfResAo = false, halfResReflections = false;
  bool denoise = true;  // --no-denoise
  // --reorder: reflections with shader execution reordering where the device enabled it
  // (HybridEffectsDesc::reflections.invocationReorder); the device is the same either way, so a pair of runs
  // measures it alone. No effect without reflections or outside --mode hybrid.
  bool invocationReorder = false;
  // --tlas-mode: HybridEffectsDesc::tlasMode (adaptive, rebuild or refit = UpdateIfPossible)
  rb::TlasBuildMode tlasMode = rb::TlasBuildMode::Adaptive;
  bool tileClassifier = false;  // --tile-classifier: HybridEffectsDesc::shadows.schedule.tileClassifier
  // --converged-tiles K: HybridEffectsDesc::shadows.schedule.convergedTiles, each converged tile traced once in K
  // frames.
  std::optional<uint32_t> convergedTiles;
  // --no-converged-tiles: the soft-shadow presets' converged tiles off (every tile traced every frame).
  bool noConvergedTiles = false;
  // --no-short-history-filter: HybridEffectsDesc::ao.disableShortHistoryFilter (to measure what the filter costs).
  bool noShortHistoryFilter = false;
  // --no-reset-rays: HybridEffectsDesc::shadows and ao.disableResetRays (to measure what reset rays buy).
  bool noResetRays = false;
  // --no-reflection-changes: HybridEffectsDesc::reflections.disableRelitResets.
  bool noReflectionChanges = false;
  // --reset-rays N: HybridEffectsDesc::shadows and ao.schedule.resetRays (0 = the SDK's default).
  uint32_t resetRays = 0;
  // --reset-follow-up N: HybridEffectsDesc::resetFollowUpFrames (0 = disableResetFollowUp); not given = the default.
  std::optional<uint32_t> resetFollowUp;
  // --converged-ao K: HybridEffectsDesc::ao.schedule.convergedTiles, likewise (AO at full resolution: --half-res
  // without ao).
  std::optional<uint32_t> convergedAo;
  // --converged-reflections K: HybridEffectsDesc::reflections.schedule.convergedTiles, likewise (reflections at full
  // resolution:
  // --half-res without reflections).
  std::optional<uint32_t> convergedReflections;
  // --converged-lights K: HybridEffectsDesc::localLights.schedule.convergedTiles, likewise (stochastic local lights).
  std::optional<uint32_t> convergedLights;
  // --adaptive EFFECT[=MS],...: adaptive rays per pixel for shadows and ao (AdaptiveRaySettings), with a GPU time
  // target in ms (0 = the uniform rays, redistributed). Unset = uniform rays.
  std::optional<float> adaptiveShadowsMs, adaptiveAoMs;
  // --adaptive's granularity keywords, for both effects: "pixel", "tile" or "tile=WxH" (AdaptiveRaySettings::
  // granularity, tileWidth, tileHeight; 0 = the SDK's default tile). Default: per tile.
  rb::AdaptiveRayGranularity adaptiveGranularity = rb::AdaptiveRayGranularity::Tile;
  // --budget MS: HybridEffectsDesc::budgetMs, the SDK's frame budget (it sets the adaptive targets: not with
  // --adaptive). Unset = none.
  std::optional<float> budgetMs;
  // --no-aliasing: HybridEffectsDesc::disableTransientAliasing (each denoiser keeps its own transient images).
  bool noAliasing = false;
  // --no-sun-cache: ReflectionEffectSettings::disableSunFromScreen (every reflection hit traces its sun ray).
  bool noSunCache = false;
  uint32_t adaptiveTileWidth = 0, adaptiveTileHeight = 0;
  // Raster mode's shadow map: --shadow-map-size (0 = none, else 1024..8192) and --pcf (taps per axis, 1..9);
  // else the preset's raster counterpart.
  std::optional<uint32_t> shadowMapSize;
  std::optional<uint32_t> pcfKernel;
  Mode mode = Mode::Hybrid;
  std::string out = "out";
  bool dump = false;
  // --compare-with DIR: with --dump, each effect image against DIR's (dump_compare.h), into stats.json.
  std::string compareWith;
  bool geometricNormals = false;
  uint32_t frames = 3;  // enough for the SDK's deferred statistics (resolved kFramesInFlight frames later)
  // Animation: the last frame shows the scene at `time` seconds; with `fps`, frame k of `frames` is at
  // time - (frames - 1 - k) / fps, so the earlier frames animate into the captured one.
  double time = 0.0;
  std::optional<double> fps;
  std::string animation;  // --animation N|NAME; empty = the scene's first animation
  // --characters N: N skinned characters from `modelsFrom` on the demo scene, each playing its animation.
  uint32_t characters = 0;
  // --perf-scene: the performance scene of perf_scene.h (shared models from `modelsFrom`, instanced on a finely
  // tessellated ground) instead of the demo scene.
  bool perfScene = false;
  uint32_t perfGroundSegments = 0;  // --perf-ground N; 0 = kPerfGroundSegments (perf_scene.h)
  uint32_t perfCopies = 0;          // --perf-copies K: K times the models' copies; 0 = 1; with --perf-ground-only none
  bool perfGroundOnly = false;      // --perf-ground-only
  // --glossy-scene: the glossy scene of glossy_scene.h (procedural, issue 30) instead of the demo scene.
  bool glossyScene = false;
  std::string modelsFrom;  // --models-from DIR (or --characters-from); empty = ../shared/scenes beside the source tree
  rb::DynamicBuildMode dynamicMode = rb::DynamicBuildMode::InFrame;  // --dynamic-builds
  std::string device;
  bool validation = false;
  bool help = false;
};

// The render command's reflection defaults (the SDK's are 0.3 and 1): the demo's copper (roughness 0.45)
// reflects, glossy pixels average 4 rays.
inline constexpr float kDefaultReflectionRoughness = 0.5f;
inline constexpr uint32_t kDefaultReflectionRays = 4;
// The render command's local-light rays (the SDK's default is 1): where a screen tile is reached by at most this many
// lights (most of the demo's), every light gets its own ray, exact; elsewhere 4 sampled rays, denoised.
inline constexpr uint32_t kDefaultLightRays = 4;

// What the preset and the explicit options amount to. Ray counts, the AO range and the reflection threshold are
// explicit; hybrid.shadows.softAngularRadiusDegrees stays 0 (the SDK's 0.5) unless --sun-radius gives one.
struct ResolvedEffects {
  // What --mode hybrid runs: the preset's effects and rays, overridden by the explicit options. The local lights
  // effect is not in any preset: main() adds it when the scene has punctual lights and --effects is not given.
  rb::HybridEffectsDesc hybrid;
  // What --mode raster draws: the preset's shadow map/PCF, overridden by --shadow-map-size/--pcf.
  rb::RasterShadowDesc raster;
  float sunRadiusDegrees = 0.0f;  // effective angular radius of the sun for soft shadows (0 = hard), for printing
};
ResolvedEffects resolve(const RenderOptions& options);

// "shadows,ao,reflections,lights" (any order and subset; "" or "none" = no effect) -> EffectSet. Returns "" or an
// error naming the bad item ("'bogus' in 'shadows,bogus' is not an effect (shadows, ao, reflections, lights)").
std::string parseEffectSet(std::string_view text, rb::EffectSet& out);
// "shadows,ao,reflections,lights" in that order; "" for no effect.
std::string effectSetToString(rb::EffectSet effects);
// "ao,reflections" (any order and subset; "" or "none" = neither) -> the effects traced at half resolution. Returns
// "" or an error naming the bad item ("'shadows' in 'ao,shadows' is not an effect with half-resolution tracing (ao,
// reflections)").
std::string parseHalfResolution(std::string_view text, bool& ao, bool& reflections);

// The cameras the command renders (--camera, and every --camera-path keyframe): coordinates within
// +-kMaxCameraCoordinate world units (squared lengths stay finite in float, and the camera-relative frame keeps a
// usable precision), eye and target at least kMinEyeTargetDistance apart relative to their largest coordinate (at
// least 1), so that the view direction has one, and a vertical fov in [kMinFovYDegrees, kMaxFovYDegrees) (below, the
// projection's 1/tan overflows a float).
inline constexpr double kMaxCameraCoordinate = 1e9;
inline constexpr double kMinEyeTargetDistance = 1e-6;
inline constexpr double kMinFovYDegrees = 0.01, kMaxFovYDegrees = 180.0;
// "" or "<what> is outside [-1e+09, 1e+09] (world units)"; `what` names the value, e.g. "ex 1e10".
std::string checkCameraCoordinate(double value, const std::string& what);
// The least distance between eye and target (see kMinEyeTargetDistance).
double minEyeTargetDistance(const glm::dvec3& eye, const glm::dvec3& target);
// "" or "<what> is outside [0.01, 180) degrees"; `what` names the value, e.g. "fovy 0".
std::string checkFovY(double degrees, const std::string& what);
// %g of v, for messages.
std::string formatNumber(double v);

// Parses argv; returns an error message naming the option and the bad value, or "" on success (options.help is
// set for -h/--help: print renderUsage() and exit 0).
std::string parseRenderOptions(int argc, char** argv, RenderOptions& options);
// The help CLI11 generates for the options parseRenderOptions accepts.
const char* renderUsage();

}  // namespace rbRender
