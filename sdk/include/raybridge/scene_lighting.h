// Sun, sky and ambient light, described once for everything the SDK shades itself: reflection hits
// (ReflectionSettings::lighting), the pure ray-traced mode (PrimaryShadingSettings::lighting) and the front end
// (HybridFrame::lighting). One resolver turns it into what the shaders read, so a zero means the same default,
// and a bad value is refused with the same message, in every effect. Local lights are a LightList (light_list.h).
//
// Thread safety: a plain value.
#pragma once

#include <cstdint>

namespace rb {

// Defaults of SceneLighting (what a zero field means unless explicitValues is set).
inline constexpr float kDefaultSunRadiance = 3.0f;  // per channel
inline constexpr float kDefaultSkyRadiance[3] = {0.45f, 0.62f, 0.9f};
inline constexpr float kDefaultAmbientIntensity = 0.4f;

// A zero-initialised SceneLighting is valid: the default sun straight up, the default sky and sky light.
struct SceneLighting {
  float sunDirection[3] = {0.0f, 0.0f, 0.0f};  // towards the sun, finite; all zero = straight up (0, 1, 0)
  float sunRadiance[3] = {0.0f, 0.0f,
                          0.0f};  // linear, the sun's colour times intensity; all zero = kDefaultSunRadiance
  float skyRadiance[3] = {0.0f, 0.0f, 0.0f};  // linear, what escaping rays return; all zero = kDefaultSkyRadiance
  float ambientIntensity = 0.0f;  // sky light on hit surfaces, times skyRadiance; 0 = kDefaultAmbientIntensity
  // No directional light: hits are lit by the sky alone (no sun, no sun shadow rays); sky and ambient keep their
  // zero-means-default rule.
  bool noSun = false;
  // Take sunRadiance, skyRadiance and ambientIntensity as given, zeros included (a black sky, no sky light): the
  // meaningful zero of an engine that hands over its own values.
  bool explicitValues = false;
};

}  // namespace rb
