// Camera conventions: right-handed, +Y up, Vulkan clip space (depth [0,1], Y down in NDC so that row 0
// of the image is the top).
#include <algorithm>
#include <cmath>

#include <glm/gtc/matrix_transform.hpp>

#include "sample_engine/scene.h"

namespace sample_engine {

glm::mat4 viewMatrix(const Camera& camera) {
  glm::vec3 forward = camera.target - camera.eye;
  glm::vec3 up(0.0f, 1.0f, 0.0f);
  // Looking straight up or down would make lookAt degenerate; nudge the up vector.
  if (glm::length(glm::cross(forward, up)) < 1e-6f * std::max(1e-6f, glm::length(forward))) up = {0, 0, -1};
  return glm::lookAtRH(camera.eye, camera.target, up);
}

glm::mat4 projectionMatrix(const Camera& camera, float aspect) {
  glm::mat4 p = glm::perspectiveRH_ZO(glm::radians(camera.fovYDegrees), aspect, camera.zNear, camera.zFar);
  p[1][1] *= -1.0f;
  return p;
}

Camera defaultCameraFor(const Bounds& bounds, float fovYDegrees) {
  Camera cam;
  cam.fovYDegrees = fovYDegrees;
  if (!bounds.valid()) return cam;
  float radius = std::max(bounds.radius(), 1e-3f);
  // Distance at which the bounding sphere fits the vertical field of view.
  float distance = radius / std::sin(glm::radians(fovYDegrees) * 0.5f);
  cam.target = bounds.center();
  cam.eye = cam.target + glm::normalize(glm::vec3(0.55f, 0.45f, 1.0f)) * distance;
  cam.zNear = std::max(distance - radius * 1.5f, distance * 1e-3f);
  cam.zNear = std::min(cam.zNear, distance * 0.1f);
  cam.zFar = distance + radius * 2.0f;
  return cam;
}

}  // namespace sample_engine
