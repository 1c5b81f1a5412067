// The many-light tests' scene: a room (ground, back wall, four pillars, a box) seen from above the front, its
// lights as KHR_lights_punctual gives them, and the error measure the tests compare images with.
#pragma once

#include <raybridge/raybridge.h>

#include <glm/glm.hpp>

#include <cstdint>
#include <vector>

#include "synthetic_gbuffer.h"

namespace rbtest {

TestScene makeRoom();
SyntheticView roomView(uint32_t width = 96, uint32_t height = 72);

rb::LightSource pointLight(glm::dvec3 p, glm::vec3 color, float candela, float range = 0.0f);
// Two point lights (one with a range), a spot and a directional light.
std::vector<rb::LightSource> roomLights();
// 32 lights: the room's four and 28 small coloured point lights with ranges, so the stochastic mode must choose.
std::vector<rb::LightSource> manyRoomLights();

// sqrt(sum |a - b|^2 / sum |b|^2) over the rgb of RGBA pixels where mask is set: b is the reference.
double relativeRmse(const std::vector<float>& a, const std::vector<float>& b, const std::vector<uint8_t>& mask);

}  // namespace rbtest
