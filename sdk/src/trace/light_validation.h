// The one check of an rb::Light, shared by every effect that takes one (the shadow pass, the many-light pass's
// list, the front end's frame light), so a light is accepted or refused the same way everywhere.
#pragma once

#include <raybridge/effects.h>
#include <raybridge/result.h>

#include <cmath>
#include <string>

namespace rb {

inline constexpr float kRadiansPerDegree = 3.14159265358979f / 180.0f;

// The vector checks of lights and lighting (rb::Light, rb::LightSource's colour, rb::SceneLighting's radiances).
inline bool finite3(const float v[3]) { return std::isfinite(v[0]) && std::isfinite(v[1]) && std::isfinite(v[2]); }
inline bool finiteNonNegative3(const float v[3]) { return finite3(v) && v[0] >= 0.0f && v[1] >= 0.0f && v[2] >= 0.0f; }

// ErrorCode::InvalidArgument naming `who` + the field ("ShadowPass: Light::position ..."), or ok. Checks: a known
// type, a finite direction, for directional lights an angular radius in [0, kMaxLightAngularRadiusDegrees), for
// point and spot lights a finite position, radius and range >= 0, for spots an outer angle in
// (0, kMaxSpotOuterAngleDegrees] (0 = kDefaultSpotOuterAngleDegrees).
Status validateLight(const Light& light, const std::string& who);

// The unit direction of a checked light: its direction normalised, or the default of an all-zero one (a sun
// overhead, a spot shining down).
void lightDirection(const Light& light, float out[3]);

// A checked spot's outer half-angle in degrees (its default for 0).
float spotOuterAngleDegrees(const Light& light);

}  // namespace rb
