// The preset table (presets.h), its names, and withPreset (hybrid_effects.h), which applies a row.
#include <raybridge/hybrid_effects.h>
#include <raybridge/presets.h>

#include <array>

namespace rb {

namespace {

struct PresetRow {
  Preset preset;
  const char* name;
  PresetDesc desc;
};

// The thesis's table, AO at half resolution and soft shadows skipping converged tiles (presets.h says why), in the
// order of the enum (checked by presetDesc).
constexpr std::array<PresetRow, kPresetCount> kPresetTable = {{
    {Preset::None, "none", {0, 0, 0, false, false, {0, 0}}},
    {Preset::HardShadows, "hard-shadows", {kEffectShadows, 1, 0, false, false, {2048, 0}}},
    {Preset::Ao, "ao", {kEffectAo, 0, 4, true, false, {0, 0}}},
    {Preset::Ao16, "ao16", {kEffectAo, 0, 16, true, false, {0, 0}}},
    {Preset::Reflections, "reflections", {kEffectReflections, 0, 0, false, false, {0, 0}}},
    {Preset::SoftShadows, "soft-shadows", {kEffectShadows, 4, 0, false, true, {4096, 4}}},
    {Preset::SoftShadows8, "soft-shadows8", {kEffectShadows, 8, 0, false, true, {8192, 8}}},
    {Preset::Low, "low", {kEffectShadows | kEffectAo, 1, 4, true, false, {2048, 0}}},
    {Preset::Medium, "medium", {kEffectShadows | kEffectAo, 4, 4, true, true, {4096, 4}}},
    {Preset::High, "high", {kThesisEffects, 4, 4, true, true, {4096, 4}}},
    {Preset::Ultra, "ultra", {kThesisEffects, 8, 16, true, true, {8192, 8}}},
}};

constexpr bool tableInEnumOrder() {
  for (size_t i = 0; i < kPresetTable.size(); ++i)
    if (size_t(kPresetTable[i].preset) != i) return false;
  return true;
}
static_assert(tableInEnumOrder(), "kPresetTable must list the presets in the order of enum Preset");

const PresetRow& row(Preset preset) {
  const size_t i = size_t(preset);
  return kPresetTable[i < kPresetTable.size() ? i : 0];
}

}  // namespace

PresetDesc presetDesc(Preset preset) { return row(preset).desc; }

const char* toString(Preset preset) { return size_t(preset) < kPresetTable.size() ? row(preset).name : "invalid"; }

std::optional<Preset> parsePreset(std::string_view name) {
  for (const PresetRow& r : kPresetTable)
    if (name == r.name) return r.preset;
  if (name == "shadows") return Preset::SoftShadows;  // the single-effect preset of earlier releases
  return std::nullopt;
}

HybridEffectsDesc withPreset(HybridEffectsDesc base, Preset preset) {
  const PresetDesc p = presetDesc(preset);
  base.effects = p.effects;
  if (p.effects & kEffectShadows) {
    base.shadows.raysPerPixel = p.shadowRaysPerPixel;
    base.shadows.schedule.convergedTiles.enabled = p.shadowConvergedTiles;
  }
  if (p.effects & kEffectAo) {
    base.ao.raysPerPixel = p.aoRaysPerPixel;
    base.ao.schedule.halfResolution = p.aoHalfResolution;
  }
  return base;
}

const char* presetNames() {
  return "none, hard-shadows, ao, ao16, reflections, soft-shadows, soft-shadows8, low, medium, high, ultra";
}

}  // namespace rb
