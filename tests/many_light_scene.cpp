// The many-light tests' scene (many_light_scene.h).
#include "many_light_scene.h"

#include <algorithm>
#include <cmath>

namespace rbtest {

TestScene makeRoom() {
  TestScene s;
  s.meshes.push_back(rbsamples::makeGrid(24.0f, 8));
  const float wallMin[3] = {-12.0f, 0.0f, -6.0f}, wallMax[3] = {12.0f, 6.0f, -5.6f};
  s.meshes.push_back(rbsamples::makeBox(wallMin, wallMax));
  const float pillarMin[3] = {-0.3f, 0.0f, -0.3f}, pillarMax[3] = {0.3f, 3.5f, 0.3f};
  s.meshes.push_back(rbsamples::makeBox(pillarMin, pillarMax));
  const float boxMin[3] = {-0.8f, 0.0f, -0.8f}, boxMax[3] = {0.8f, 1.2f, 0.8f};
  s.meshes.push_back(rbsamples::makeBox(boxMin, boxMax));
  s.instances.push_back({0, translation(0, 0, 0)});
  s.instances.push_back({1, translation(0, 0, 0)});
  for (float x : {-4.0f, -1.5f, 1.5f, 4.0f}) s.instances.push_back({2, translation(x, 0, -2.5f)});
  s.instances.push_back({3, translation(2.5f, 0, 1.5f)});
  return s;
}

SyntheticView roomView(uint32_t width, uint32_t height) {
  SyntheticView v;
  v.eye = {0.0, 6.0, 10.0};
  v.target = {0.0, 0.5, -1.0};
  v.fovYDegrees = 55.0;
  v.width = width;
  v.height = height;
  return v;
}

rb::LightSource pointLight(glm::dvec3 p, glm::vec3 color, float candela, float range) {
  rb::LightSource l;
  l.light.type = rb::LightType::Point;
  for (int i = 0; i < 3; ++i) l.light.position[i] = p[i], l.color[i] = color[i];
  l.intensity = candela;
  l.light.range = range;
  return l;
}

std::vector<rb::LightSource> roomLights() {
  std::vector<rb::LightSource> lights;
  lights.push_back(pointLight({-3.0, 2.5, 0.5}, {1.0f, 0.6f, 0.3f}, 12.0f));
  lights.push_back(pointLight({3.5, 2.0, -1.0}, {0.3f, 0.6f, 1.0f}, 9.0f, 7.0f));
  rb::LightSource spot;
  spot.light.type = rb::LightType::Spot;
  spot.light.position[0] = 0.5, spot.light.position[1] = 5.0, spot.light.position[2] = 2.0;
  spot.light.direction[0] = -0.1f, spot.light.direction[1] = -1.0f, spot.light.direction[2] = -0.3f;
  spot.light.spotOuterAngleDegrees = 35.0f;
  spot.spotInnerAngleDegrees = 20.0f;
  spot.intensity = 40.0f;
  lights.push_back(spot);
  rb::LightSource sun;
  sun.light.direction[0] = 0.4f, sun.light.direction[1] = 1.0f, sun.light.direction[2] = 0.3f;
  sun.color[1] = 0.95f, sun.color[2] = 0.85f;
  sun.intensity = 0.6f;
  lights.push_back(sun);
  return lights;
}

std::vector<rb::LightSource> manyRoomLights() {
  std::vector<rb::LightSource> lights = roomLights();
  for (int k = 0; k < 28; ++k) {
    double x = -6.0 + 12.0 * ((k * 7) % 28) / 27.0, z = -4.5 + 7.0 * ((k * 11) % 28) / 27.0;
    glm::vec3 color(0.3f + 0.7f * float(k % 3 == 0), 0.3f + 0.7f * float(k % 3 == 1), 0.3f + 0.7f * float(k % 3 == 2));
    lights.push_back(pointLight({x, 0.6 + 0.1 * (k % 5), z}, color, 1.5f, 4.0f));
  }
  return lights;
}

double relativeRmse(const std::vector<float>& a, const std::vector<float>& b, const std::vector<uint8_t>& mask) {
  double se = 0.0, ref = 0.0;
  for (size_t i = 0; i < mask.size(); ++i) {
    if (!mask[i]) continue;
    for (int c = 0; c < 3; ++c) {
      double d = double(a[4 * i + c]) - double(b[4 * i + c]);
      se += d * d;
      ref += double(b[4 * i + c]) * b[4 * i + c];
    }
  }
  return std::sqrt(se / std::max(ref, 1e-30));
}

}  // namespace rbtest
