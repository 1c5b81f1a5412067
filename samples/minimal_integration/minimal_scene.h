// The minimal integration's procedural scene, camera path and sun, shared by the program and its test (which
// traces the same triangles with Embree). Plain C++: no Vulkan, no Raybridge.
#pragma once

#include <cmath>
#include <cstdint>
#include <vector>

namespace minimal {

// World-space triangles (the instances are identity transforms), counter-clockwise seen from outside.
struct Mesh {
  const char* name = "";
  std::vector<float> positions;   // xyz per vertex
  std::vector<uint32_t> indices;  // three per triangle
};

inline void addQuad(Mesh& m, const float (&a)[3], const float (&b)[3], const float (&c)[3], const float (&d)[3]) {
  const uint32_t base = uint32_t(m.positions.size() / 3);
  for (const float* p : {a, b, c, d}) m.positions.insert(m.positions.end(), {p[0], p[1], p[2]});
  m.indices.insert(m.indices.end(), {base, base + 1, base + 2, base, base + 2, base + 3});
}

inline Mesh box(const char* name, float x0, float y0, float z0, float x1, float y1, float z1) {
  Mesh m{name, {}, {}};
  addQuad(m, {x0, y1, z0}, {x0, y1, z1}, {x1, y1, z1}, {x1, y1, z0});  // +Y
  addQuad(m, {x0, y0, z0}, {x1, y0, z0}, {x1, y0, z1}, {x0, y0, z1});  // -Y
  addQuad(m, {x1, y0, z0}, {x1, y1, z0}, {x1, y1, z1}, {x1, y0, z1});  // +X
  addQuad(m, {x0, y0, z0}, {x0, y0, z1}, {x0, y1, z1}, {x0, y1, z0});  // -X
  addQuad(m, {x0, y0, z1}, {x1, y0, z1}, {x1, y1, z1}, {x0, y1, z1});  // +Z
  addQuad(m, {x0, y0, z0}, {x0, y1, z0}, {x1, y1, z0}, {x1, y0, z0});  // -Z
  return m;
}

inline Mesh sphere(const char* name, float cx, float cy, float cz, float r, uint32_t slices, uint32_t stacks) {
  Mesh m{name, {}, {}};
  for (uint32_t i = 0; i <= stacks; ++i) {
    const float theta = 3.14159265f * float(i) / float(stacks);
    for (uint32_t j = 0; j <= slices; ++j) {
      const float phi = 2.0f * 3.14159265f * float(j) / float(slices);
      m.positions.insert(m.positions.end(), {cx + r * std::sin(theta) * std::cos(phi), cy + r * std::cos(theta),
                                             cz - r * std::sin(theta) * std::sin(phi)});
    }
  }
  for (uint32_t i = 0; i < stacks; ++i) {
    for (uint32_t j = 0; j < slices; ++j) {
      const uint32_t a = i * (slices + 1) + j, b = a + slices + 1;
      if (i != 0) m.indices.insert(m.indices.end(), {a, b, a + 1});
      if (i + 1 != stacks) m.indices.insert(m.indices.end(), {a + 1, b, b + 1});
    }
  }
  return m;
}

// A ground quad, two boxes, a sphere and a slab floating above the ground (whose shadow is detached from it).
inline std::vector<Mesh> makeScene() {
  std::vector<Mesh> scene;
  Mesh ground{"ground", {}, {}};
  addQuad(ground, {-20, 0, -20}, {-20, 0, 20}, {20, 0, 20}, {20, 0, -20});
  scene.push_back(ground);
  scene.push_back(box("box", -2.6f, 0.0f, -0.8f, -1.2f, 1.4f, 0.6f));
  scene.push_back(box("tower", 1.2f, 0.0f, -2.2f, 2.2f, 2.4f, -1.2f));
  scene.push_back(sphere("sphere", 0.2f, 0.8f, 1.6f, 0.8f, 32, 16));
  scene.push_back(box("floating slab", 2.0f, 2.0f, 0.8f, 4.0f, 2.2f, 2.6f));
  return scene;
}

inline constexpr float kToSun[3] = {0.48f, 0.78f, 0.40f};  // direction towards the sun (normalised by users)
inline constexpr float kFovYDegrees = 50.0f;
inline constexpr float kNearPlane = 0.1f;

// The camera strafes along +X by 0.15 units a frame, so every pixel has a motion vector.
inline void cameraAt(uint32_t frame, double eye[3], double target[3]) {
  eye[0] = -2.5 + 0.15 * frame, eye[1] = 3.4, eye[2] = 6.5;
  target[0] = 0.3 + 0.15 * frame, target[1] = 0.6, target[2] = 0.0;
}

// Column-major right-handed look-at (GLM's lookAt), world up +Y.
inline void viewMatrix(const double eye[3], const double target[3], float m[16]) {
  double f[3] = {target[0] - eye[0], target[1] - eye[1], target[2] - eye[2]};
  double fl = std::sqrt(f[0] * f[0] + f[1] * f[1] + f[2] * f[2]);
  for (double& c : f) c /= fl;
  double s[3] = {-f[2], 0.0, f[0]};  // cross(f, up)
  double sl = std::sqrt(s[0] * s[0] + s[2] * s[2]);
  for (double& c : s) c /= sl;
  const double u[3] = {s[1] * f[2] - s[2] * f[1], s[2] * f[0] - s[0] * f[2], s[0] * f[1] - s[1] * f[0]};
  const double t[3] = {-(s[0] * eye[0] + s[1] * eye[1] + s[2] * eye[2]),
                       -(u[0] * eye[0] + u[1] * eye[1] + u[2] * eye[2]), f[0] * eye[0] + f[1] * eye[1] + f[2] * eye[2]};
  const double cm[16] = {s[0], u[0], -f[0], 0, s[1], u[1], -f[1], 0, s[2], u[2], -f[2], 0, t[0], t[1], t[2], 1};
  for (int i = 0; i < 16; ++i) m[i] = float(cm[i]);
}

// Column-major reversed-Z projection with an infinite far plane, Vulkan clip space with +Y down: depth = near
// / view distance (1 at the near plane, 0 at infinity), the world's up at the top of the image.
inline void reversedInfiniteProjection(float fovYDegrees, float aspect, float nearPlane, float m[16]) {
  const float t = std::tan(fovYDegrees * 3.14159265f / 360.0f);
  for (int i = 0; i < 16; ++i) m[i] = 0.0f;
  m[0] = 1.0f / (aspect * t);
  m[5] = -1.0f / t;
  m[11] = -1.0f;
  m[14] = nearPlane;
}

inline void multiply(const float a[16], const float b[16], float out[16]) {  // out = a * b, column-major
  for (int c = 0; c < 4; ++c) {
    for (int r = 0; r < 4; ++r) {
      float sum = 0.0f;
      for (int k = 0; k < 4; ++k) sum += a[k * 4 + r] * b[c * 4 + k];
      out[c * 4 + r] = sum;
    }
  }
}

}  // namespace minimal
