// Command line of raybridge-render: parsing and validation (every error names the option and the bad value).
#pragma once

#include <cstdint>
#include <optional>
#include <string>

#include <glm/glm.hpp>

#include "raybridge_sample_engine_adapter.h"

namespace rbRender {

enum class Mode { Raster, Hybrid };

struct RenderOptions {
  std::string scene;  // empty = the engine's procedural demo scene
  uint32_t width = 1280, height = 720;
  // Eye, target, vertical fov in degrees; empty = the scene's own camera, else framed on the scene bounds.
  std::optional<glm::vec3> eye, target;
  float fovYDegrees = 0.0f;
  std::optional<glm::vec3> sun;  // towards the sun; empty = the scene's sun, else the engine's default
  // Effects and their quality: the preset gives defaults, explicit options win (see resolve()).
  rbAdapter::Preset preset = rbAdapter::Preset::High;
  std::optional<rbAdapter::EffectSet> effects;  // --effects: overrides the preset's set
  std::optional<float> sunRadiusDegrees;        // --sun-radius; else 0.5 for soft presets, 0 for hard ones
  std::optional<uint32_t> shadowRays;           // --shadow-rays; else the preset's
  std::optional<uint32_t> aoRays;               // --ao-rays; else the preset's (4 where it has no AO)
  std::optional<float> aoRange;                 // --ao-range; else the SDK's 1.0
  rb::AoEstimator aoEstimator = rb::AoEstimator::Binary;  // --ao-estimator binary|distance
  std::optional<float> reflectionRoughness;     // --reflection-roughness threshold; else the default below
  std::optional<uint32_t> reflectionRays;       // --reflection-rays; else the default below
  bool denoise = true;                          // --no-denoise
  Mode mode = Mode::Hybrid;
  std::string out = "out";
  bool dump = false;
  bool geometricNormals = false;
  uint32_t frames = 3;  // enough for the SDK's deferred statistics (resolved kFramesInFlight frames later)
  // Animation: the last frame shows the scene at `time` seconds; with `fps`, frame k of `frames` is at
  // time - (frames - 1 - k) / fps, so the earlier frames animate into the captured one.
  double time = 0.0;
  std::optional<double> fps;
  std::string animation;  // --animation N|NAME; empty = the scene's first animation
  // --characters N: N skinned characters from `charactersFrom` on the demo scene, each playing its animation.
  uint32_t characters = 0;
  std::string charactersFrom;  // --characters-from DIR; empty = ../shared/scenes beside the source tree
  rb::DynamicBuildMode dynamicMode = rb::DynamicBuildMode::InFrame;  // --dynamic-builds
  std::string device;
  bool validation = false;
  bool help = false;
};

// What the preset and the explicit options amount to.
struct ResolvedEffects {
  rbAdapter::EffectSet effects = 0;
  float sunRadiusDegrees = 0.0f;  // 0 = hard shadows
  uint32_t shadowRays = 1;        // effective rays per pixel (1 for hard shadows)
  uint32_t aoRays = 4;
  float aoRange = 1.0f;
  float reflectionRoughness = 0.3f;
  uint32_t reflectionRays = 1;
};
ResolvedEffects resolve(const RenderOptions& options);

// Parses argv; returns an error message naming the problem, or "" on success.
std::string parseRenderOptions(int argc, char** argv, RenderOptions& options);
const char* renderUsage();

}  // namespace rbRender
