#include "scene_meshes.h"

#include <algorithm>
#include <cmath>

namespace rbbench {

Transform translation(float x, float y, float z) { return {1, 0, 0, x, 0, 1, 0, y, 0, 0, 1, z}; }

Transform scaledTranslation(float s, float x, float y, float z) { return {s, 0, 0, x, 0, s, 0, y, 0, 0, s, z}; }

void setTransform(rb::Instance& instance, const Transform& t) { std::copy(t.begin(), t.end(), instance.transform); }

rbsamples::CpuMesh groundWithAbout(uint64_t triangles, float size) {
  uint32_t cells = std::max<uint32_t>(1, static_cast<uint32_t>(std::lround(std::sqrt(double(triangles) / 2.0))));
  return rbsamples::makeBumpyGrid(size, cells, size * 0.02f);
}

void Bounds::add(const rbsamples::CpuMesh& mesh, const Transform& t) {
  const size_t n = mesh.positions.size() / 3;
  for (size_t v = 0; v < n; ++v) {
    const float* p = &mesh.positions[3 * v];
    for (int r = 0; r < 3; ++r) {
      float w = t[4 * r] * p[0] + t[4 * r + 1] * p[1] + t[4 * r + 2] * p[2] + t[4 * r + 3];
      min[r] = std::min(min[r], w);
      max[r] = std::max(max[r], w);
    }
  }
}

void Bounds::add(const Bounds& b) {
  for (int r = 0; r < 3; ++r) {
    min[r] = std::min(min[r], b.min[r]);
    max[r] = std::max(max[r], b.max[r]);
  }
}

Bounds boundsOf(const rbsamples::CpuMesh& mesh) {
  Bounds b;
  b.add(mesh, translation(0, 0, 0));
  return b;
}

rb::PrimaryRayCamera cameraFraming(const Bounds& b, std::array<float, 3> dir) {
  rb::PrimaryRayCamera cam;
  float centre[3], radius = 0.0f;
  for (int i = 0; i < 3; ++i) {
    centre[i] = 0.5f * (b.min[i] + b.max[i]);
    float half = 0.5f * (b.max[i] - b.min[i]);
    radius += half * half;
  }
  radius = std::max(std::sqrt(radius), 1e-3f);
  const float fov = 50.0f;
  // Distance at which a sphere of `radius` fits the vertical field of view, pulled in a little so the
  // geometry, not the sky, fills most of the image.
  float dist = radius / std::sin(fov * 0.5f * 3.14159265f / 180.0f) * 0.6f;
  float len = std::sqrt(dir[0] * dir[0] + dir[1] * dir[1] + dir[2] * dir[2]);
  for (int i = 0; i < 3; ++i) {
    cam.eye[i] = centre[i] + dir[i] / len * dist;
    cam.target[i] = centre[i];
  }
  cam.verticalFovDegrees = fov;
  return cam;
}

rb::PrimaryRayCamera cameraOverGround(float size) {
  // Pitched about 72 degrees down with a 50 degree vertical field of view: the top image row meets the ground
  // about a quarter of its size ahead, the corners stay inside its half-width.
  rb::PrimaryRayCamera cam;
  cam.eye[0] = 0.0f;
  cam.eye[1] = 0.35f * size;
  cam.eye[2] = 0.10f * size;
  cam.target[2] = -0.05f * size;
  cam.verticalFovDegrees = 50.0f;
  return cam;
}

std::vector<Transform> gridPlacement(uint32_t count, float spacing) {
  uint32_t side = static_cast<uint32_t>(std::ceil(std::sqrt(double(count))));
  std::vector<Transform> out;
  out.reserve(count);
  float origin = -0.5f * spacing * float(side - 1);
  for (uint32_t i = 0; i < count; ++i) {
    out.push_back(translation(origin + spacing * float(i % side), 0.0f, origin + spacing * float(i / side)));
  }
  return out;
}

}  // namespace rbbench
