// Command line of raybridge-effects-bench: parsing and validation (every error names the option and the value).
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <raybridge/presets.h>

namespace rbEffects {

// The motion scenario's cases, in the order they run (motion_sweep.cpp makes them).
inline constexpr const char* kMotionCases[] = {"still", "pan", "turn", "walkers", "teleport", "lamp_jump", "door"};

struct Options {
  std::string scenario = "speed-vs-error";
  rb::EffectSet effects = rb::kThesisEffects;  // motion: every effect unless --effects says otherwise
  bool effectsGiven = false;
  uint32_t characters = 3;            // motion: walkers
  bool noAntiLag = false;             // motion: DenoiseSettings::disableAntiLag
  bool noShortHistoryFilter = false;  // motion: AoEffectSettings::disableShortHistoryFilter
  bool noResetRays = false;           // motion: Shadow/AoEffectSettings::disableResetRays
  bool noReflectionChanges = false;   // motion: ReflectionEffectSettings::disableRelitResets
  uint32_t resetRaysFactor = 0;       // motion: RaySchedule::resetRays = this x the rays; 0 = the SDK's default
  // motion: HybridEffectsDesc::resetFollowUpFrames (0 = disableResetFollowUp); not given = the SDK's default
  std::optional<uint32_t> resetFollowUp;
  bool noChangeResets = false;           // motion: HybridEffectsDesc::disableChangeResets
  bool convergedTiles = false;           // motion: RaySchedule::convergedTiles on for every effect
  std::vector<uint32_t> motionRays;      // motion: rays per pixel of the denoised sequences; empty = 1, 4, 16
  std::vector<std::string> motionCases;  // motion: the cases to run (rbEffects::kMotionCases); empty = all
  std::string scenes;                    // motion: character models; empty = ../shared/scenes beside the source tree
  // Empty: 1920x1080 on a GPU, 320x180 on a CPU device (lavapipe); --quick: 160x90.
  std::optional<uint32_t> width, height;
  std::string out;     // JSON file; empty = none
  std::string images;  // folder for the PNGs (FLIP input); empty = none
  // Total rays per pixel of each effect's reference; unset = defaults chosen from the device and --quick.
  std::optional<uint32_t> referenceRaysShadows, referenceRaysAo, referenceRaysReflections;
  std::string rawRateJson;              // raybridge-bench JSON with the gigarays scenario
  std::optional<uint32_t> timedFrames;  // frames whose median is reported; unset = 7 on a GPU, 3 on a CPU
  float aoRange = 1.0f;                 // world units: the traced AO range and the SSAO radius
  float reflectionRoughness = 1.0f;     // traced reflections threshold: 1 = every surface traces
  bool quick = false;
  std::string device;
  bool validation = false;  // also RAYBRIDGE_VALIDATION=1
  bool help = false;
  std::string commandLine;  // as given, for the JSON
};

// Parses argv; returns an error naming the option and the bad value, or "" on success (options.help is set for
// -h/--help).
std::string parseOptions(int argc, char** argv, Options& options);
// The help CLI11 generates for these options.
const char* usage();

}  // namespace rbEffects
