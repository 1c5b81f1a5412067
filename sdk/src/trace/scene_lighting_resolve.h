// The one resolver of rb::SceneLighting: defaults applied, the sun direction normalised, bad values refused with a
// message naming the field. The reflection pass and the primary shading pass fill their constants from it.
#pragma once

#include <raybridge/result.h>
#include <raybridge/scene_lighting.h>

#include <string>

namespace rb {

struct ResolvedLighting {
  float sunDirection[3];  // unit length
  float sunRadiance[3];   // 0 with noSun
  float skyRadiance[3];
  float ambientIntensity;
};

// `field` names the SceneLighting in messages ("ReflectionPass: ReflectionSettings::lighting").
Result<ResolvedLighting> resolveSceneLighting(const SceneLighting& lighting, const std::string& field);

// Into a pass's push constants (ReflectionConstants, PrimaryShadingConstants: the same member names).
template <typename Constants>
void fillLighting(const ResolvedLighting& l, Constants& pc) {
  for (int i = 0; i < 3; ++i) {
    pc.sunDirection[i] = l.sunDirection[i];
    pc.sunRadiance[i] = l.sunRadiance[i];
    pc.skyRadiance[i] = l.skyRadiance[i];
  }
  pc.ambientIntensity = l.ambientIntensity;
}

}  // namespace rb
