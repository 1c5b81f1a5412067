#include "scene_lighting_resolve.h"

#include <cmath>

#include "light_validation.h"

namespace rb {

namespace {

bool isZero(const float c[3]) { return c[0] == 0.0f && c[1] == 0.0f && c[2] == 0.0f; }

}  // namespace

Result<ResolvedLighting> resolveSceneLighting(const SceneLighting& l, const std::string& field) {
  auto invalid = [&](const std::string& m) { return Error{ErrorCode::InvalidArgument, VK_SUCCESS, field + "." + m}; };
  const bool sunUnset = isZero(l.sunDirection);
  const float direction[3] = {l.sunDirection[0], sunUnset ? 1.0f : l.sunDirection[1], l.sunDirection[2]};
  const float length = std::sqrt(direction[0] * direction[0] + direction[1] * direction[1] +
                                 direction[2] * direction[2]);
  if (!std::isfinite(length)) return invalid("sunDirection must be finite");
  if (!finiteNonNegative3(l.sunRadiance)) return invalid("sunRadiance must be finite and >= 0");
  if (!finiteNonNegative3(l.skyRadiance)) return invalid("skyRadiance must be finite and >= 0");
  if (!(std::isfinite(l.ambientIntensity) && l.ambientIntensity >= 0.0f)) {
    return invalid("ambientIntensity " + std::to_string(l.ambientIntensity) + " must be finite and >= 0");
  }
  // Zero means the default, unless the engine says its zeros are meant (a black sky, no sky light).
  const bool defaultSun = !l.explicitValues && isZero(l.sunRadiance);
  const bool defaultSky = !l.explicitValues && isZero(l.skyRadiance);
  ResolvedLighting out;
  for (int i = 0; i < 3; ++i) {
    out.sunDirection[i] = direction[i] / length;
    out.sunRadiance[i] = l.noSun ? 0.0f : defaultSun ? kDefaultSunRadiance : l.sunRadiance[i];
    out.skyRadiance[i] = defaultSky ? kDefaultSkyRadiance[i] : l.skyRadiance[i];
  }
  out.ambientIntensity = l.ambientIntensity == 0.0f && !l.explicitValues ? kDefaultAmbientIntensity
                                                                         : l.ambientIntensity;
  return out;
}

}  // namespace rb
