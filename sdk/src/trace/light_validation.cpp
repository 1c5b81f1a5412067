#include "light_validation.h"

#include <cmath>

namespace rb {

Status validateLight(const Light& l, const std::string& who) {
  auto invalid = [&](const std::string& m) { return Error{ErrorCode::InvalidArgument, VK_SUCCESS, who + m}; };
  if (l.type != LightType::Directional && l.type != LightType::Point && l.type != LightType::Spot)
    return invalid("Light::type has an unknown value " + std::to_string(int(l.type)));
  if (!finite3(l.direction)) return invalid("Light::direction must be a finite vector");
  if (l.type == LightType::Directional) {
    if (!(l.angularRadiusDegrees >= 0.0f && l.angularRadiusDegrees < kMaxLightAngularRadiusDegrees))
      return invalid("Light::angularRadiusDegrees " + std::to_string(l.angularRadiusDegrees) + " is outside [0, " +
                     std::to_string(int(kMaxLightAngularRadiusDegrees)) + ")");
    return {};
  }
  for (double p : l.position) {
    if (!std::isfinite(p)) return invalid("Light::position must be finite");
  }
  if (!(l.radius >= 0.0f && std::isfinite(l.radius))) return invalid("Light::radius must be finite and >= 0");
  if (!(l.range >= 0.0f && std::isfinite(l.range)))
    return invalid("Light::range must be finite and >= 0 (0 = unlimited)");
  if (l.type == LightType::Spot) {
    const float outer = spotOuterAngleDegrees(l);
    if (!(outer > 0.0f && outer <= kMaxSpotOuterAngleDegrees))
      return invalid("Light::spotOuterAngleDegrees " + std::to_string(outer) + " is outside (0, " +
                     std::to_string(int(kMaxSpotOuterAngleDegrees)) + "]");
  }
  return {};
}

void lightDirection(const Light& l, float out[3]) {
  float d[3] = {l.direction[0], l.direction[1], l.direction[2]};
  if (d[0] == 0.0f && d[1] == 0.0f && d[2] == 0.0f) d[1] = l.type == LightType::Spot ? -1.0f : 1.0f;
  const float len = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
  for (int i = 0; i < 3; ++i) out[i] = d[i] / len;
}

float spotOuterAngleDegrees(const Light& l) {
  return l.spotOuterAngleDegrees == 0.0f ? kDefaultSpotOuterAngleDegrees : l.spotOuterAngleDegrees;
}

}  // namespace rb
