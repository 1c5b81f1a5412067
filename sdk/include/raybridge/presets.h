// Quality presets: the thesis's table of effect sets and ray counts, with the raster counterpart an engine
// draws when it renders without Raybridge (its shadow-map size and PCF kernel), so both modes of one preset
// can be compared.
//
//   preset          shadow rays       AO rays      reflections  raster shadow map, PCF
//   none                 0               0             no        none
//   hard-shadows         1               0             no        2048
//   ao                   0               4, half res   no        none
//   ao16                 0              16, half res   no        none
//   reflections          0               0             yes       none
//   soft-shadows         4, converged    0             no        4096, PCF 4
//   soft-shadows8        8, converged    0             no        8192, PCF 8
//   low                  1               4, half res   no        2048
//   medium               4, converged    4, half res   no        4096, PCF 4
//   high                 4, converged    4, half res   yes       4096, PCF 4
//   ultra                8, converged   16, half res   yes       8192, PCF 8
//
// One shadow ray means hard shadows (towards the light's centre); more rays sample the light's disk.
// Every preset with AO traces it at half resolution (AoSettings::schedule.halfResolution: a quarter of the pixels, a
// depth-aware upsample): a fraction of the time at a lower denoised error for 1 to 16 rays (docs/performance.md,
// "Half resolution"). Reflections stay at full resolution: at half resolution they are several times faster but
// their denoised error is several times worse (same section). Set the flag back to false for the
// thesis's full-resolution AO.
// Every soft-shadow preset skips the shadow tiles whose denoised history has converged
// (ShadowSettings::schedule.convergedTiles, "converged" above): under motion it costs no lag, because the change masks
// of HybridEffects (hybrid_effects.h) make the tiles a known change touches trace on that change's own frame, and the
// still error stays within 2% (docs/effects.md, "Motion": converged tiles under motion). The other effects keep every
// tile: AO is at half resolution, which converged tiles exclude; a local light's shadow falls outside the boxes that
// moved, so a converged tile there would show it late; reflections gain nothing measurable. Set the flag back to false
// for every tile traced every frame.
//
// Thread safety: plain data and pure functions.
#pragma once

#include <cstdint>
#include <optional>
#include <string_view>

namespace rb {

// The effects a HybridEffects object runs (see hybrid_effects.h). An effect not in the set has no pass, no
// denoiser and no memory.
enum EffectBits : uint32_t {
  kEffectShadows = 1u << 0,      // ShadowPass: visibility of the frame's light
  kEffectAo = 1u << 1,           // AoPass: ambient occlusion
  kEffectReflections = 1u << 2,  // ReflectionPass: mirror and glossy reflections
  kEffectLocalLights = 1u << 3,  // ManyLightPass: shadowed irradiance from the frame's light list
};
using EffectSet = uint32_t;
inline constexpr EffectSet kAllEffects = kEffectShadows | kEffectAo | kEffectReflections | kEffectLocalLights;
// The thesis's three effects: what the High and Ultra presets run (local lights are enabled on top of a preset).
inline constexpr EffectSet kThesisEffects = kEffectShadows | kEffectAo | kEffectReflections;

enum class Preset : uint8_t {
  None = 0,  // default: no effect
  HardShadows,
  Ao,
  Ao16,
  Reflections,
  SoftShadows,
  SoftShadows8,
  Low,
  Medium,
  High,
  Ultra,
  Count
};
inline constexpr uint32_t kPresetCount = uint32_t(Preset::Count);

// The raster counterpart of a preset: a shadow map of mapSize texels squared filtered by a PCF kernel of
// pcfKernel x pcfKernel taps (0 = one hardware-filtered tap), or no shadow map at all (mapSize 0).
struct RasterShadowDesc {
  uint32_t mapSize = 0;    // 0 = the preset has no shadow map: the raster mode draws the sun unshadowed
  uint32_t pcfKernel = 0;  // taps per axis; 0 = a single 2x2 hardware compare
};

struct PresetDesc {
  EffectSet effects = 0;
  uint32_t shadowRaysPerPixel = 0;  // 0 when the preset has no shadows; 1 = hard shadows
  uint32_t aoRaysPerPixel = 0;      // 0 when the preset has no AO
  bool aoHalfResolution = false;    // AoSettings::schedule.halfResolution (true for every preset with AO, above)
  // ShadowSettings::schedule.convergedTiles.enabled, at the default refresh period (true for every soft-shadow
  // preset, above).
  bool shadowConvergedTiles = false;
  RasterShadowDesc raster{};
};

PresetDesc presetDesc(Preset preset);
// "none", "hard-shadows", "ao", "ao16", "reflections", "soft-shadows", "soft-shadows8", "low", "medium", "high",
// "ultra".
const char* toString(Preset preset);
// The names above, and the names of earlier releases: "shadows" (= soft-shadows).
std::optional<Preset> parsePreset(std::string_view name);
// "none, hard-shadows, ao, ..." for help texts and error messages.
const char* presetNames();

}  // namespace rb
