// Procedural meshes. Every generator emits outward-facing counter-clockwise triangles, per-vertex
// normals, UVs and tangents, and exactly the triangle count its *TriangleCount() function promises.
#include <cmath>
#include <numbers>

#include "sample_engine/procedural.h"

namespace sample_engine {
namespace {

constexpr float kPi = std::numbers::pi_v<float>;

struct Builder {
  MeshData mesh;
  uint32_t add(const glm::vec3& p, const glm::vec3& n, const glm::vec2& uv, const glm::vec3& tangent) {
    mesh.positions.push_back(p);
    mesh.normals.push_back(n);
    mesh.uvs.push_back(uv);
    mesh.tangents.emplace_back(tangent, 1.0f);
    return static_cast<uint32_t>(mesh.positions.size() - 1);
  }
  void tri(uint32_t a, uint32_t b, uint32_t c) { mesh.indices.insert(mesh.indices.end(), {a, b, c}); }
};

// Grid of (cols+1) x (rows+1) vertices starting at `first`, row-major; emits two triangles per cell with
// the (a, b, c), (b, d, c) pattern where a = (col, row), b = (col+1, row), c = (col, row+1).
void gridTriangles(Builder& b, uint32_t first, uint32_t cols, uint32_t rows) {
  for (uint32_t r = 0; r < rows; ++r)
    for (uint32_t c = 0; c < cols; ++c) {
      uint32_t a = first + r * (cols + 1) + c;
      uint32_t bb = a + 1, cc = a + cols + 1, d = cc + 1;
      b.tri(a, bb, cc);
      b.tri(bb, d, cc);
    }
}

}  // namespace

uint32_t planeTriangleCount(uint32_t sx, uint32_t sz) { return 2 * sx * sz; }
uint32_t boxTriangleCount(uint32_t s) { return 12 * s * s; }
uint32_t sphereTriangleCount(uint32_t slices, uint32_t stacks) { return 2 * slices * (stacks - 1); }
uint32_t cylinderTriangleCount(uint32_t slices, uint32_t h, bool capped) {
  return 2 * slices * h + (capped ? 2 * slices : 0);
}
uint32_t archTriangleCount(uint32_t a, uint32_t t) { return 2 * a * t; }

MeshData makePlane(float sizeX, float sizeZ, uint32_t segX, uint32_t segZ) {
  segX = std::max(segX, 1u);
  segZ = std::max(segZ, 1u);
  Builder b;
  b.mesh.name = "plane";
  // Rows run towards -Z so that (col+1, row) x (col, row+1) winds counter-clockwise seen from +Y.
  for (uint32_t r = 0; r <= segZ; ++r)
    for (uint32_t c = 0; c <= segX; ++c) {
      float u = float(c) / segX, v = float(r) / segZ;
      b.add({(u - 0.5f) * sizeX, 0.0f, (0.5f - v) * sizeZ}, {0, 1, 0}, {u, 1.0f - v}, {1, 0, 0});
    }
  gridTriangles(b, 0, segX, segZ);
  return b.mesh;
}

MeshData makeBox(const glm::vec3& size, uint32_t segments) {
  segments = std::max(segments, 1u);
  struct Face {
    glm::vec3 n, u, v;
  };
  // cross(u, v) = n for every face, so the grid pattern winds outward.
  const Face faces[6] = {{{1, 0, 0}, {0, 0, -1}, {0, 1, 0}}, {{-1, 0, 0}, {0, 0, 1}, {0, 1, 0}},
                         {{0, 1, 0}, {1, 0, 0}, {0, 0, -1}}, {{0, -1, 0}, {1, 0, 0}, {0, 0, 1}},
                         {{0, 0, 1}, {1, 0, 0}, {0, 1, 0}},  {{0, 0, -1}, {-1, 0, 0}, {0, 1, 0}}};
  Builder b;
  b.mesh.name = "box";
  const glm::vec3 half = size * 0.5f;
  for (const Face& f : faces) {
    uint32_t first = static_cast<uint32_t>(b.mesh.positions.size());
    glm::vec3 center = f.n * half, extentU = f.u * half, extentV = f.v * half;
    for (uint32_t r = 0; r <= segments; ++r)
      for (uint32_t c = 0; c <= segments; ++c) {
        float s = float(c) / segments, t = float(r) / segments;
        glm::vec3 p = center + extentU * (2.0f * s - 1.0f) + extentV * (2.0f * t - 1.0f);
        b.add(p, f.n, {s, 1.0f - t}, f.u);
      }
    gridTriangles(b, first, segments, segments);
  }
  return b.mesh;
}

MeshData makeSphere(float radius, uint32_t slices, uint32_t stacks) {
  slices = std::max(slices, 3u);
  stacks = std::max(stacks, 2u);
  Builder b;
  b.mesh.name = "sphere";
  auto dir = [](float theta, float phi) {
    return glm::vec3(std::sin(theta) * std::cos(phi), std::cos(theta), std::sin(theta) * std::sin(phi));
  };
  auto tangent = [](float phi) { return glm::vec3(-std::sin(phi), 0.0f, std::cos(phi)); };
  // One pole vertex per slice so each cap triangle gets its own UV.
  uint32_t topPole = 0;
  for (uint32_t i = 0; i < slices; ++i) {
    float phi = (i + 0.5f) / slices * 2.0f * kPi;
    b.add({0, radius, 0}, {0, 1, 0}, {(i + 0.5f) / slices, 0.0f}, tangent(phi));
  }
  uint32_t firstRing = static_cast<uint32_t>(b.mesh.positions.size());
  for (uint32_t j = 1; j < stacks; ++j)
    for (uint32_t i = 0; i <= slices; ++i) {
      float theta = float(j) / stacks * kPi, phi = float(i) / slices * 2.0f * kPi;
      glm::vec3 n = dir(theta, phi);
      b.add(n * radius, n, {float(i) / slices, float(j) / stacks}, tangent(phi));
    }
  uint32_t bottomPole = static_cast<uint32_t>(b.mesh.positions.size());
  for (uint32_t i = 0; i < slices; ++i) {
    float phi = (i + 0.5f) / slices * 2.0f * kPi;
    b.add({0, -radius, 0}, {0, -1, 0}, {(i + 0.5f) / slices, 1.0f}, tangent(phi));
  }
  auto ring = [&](uint32_t j, uint32_t i) { return firstRing + (j - 1) * (slices + 1) + i; };
  for (uint32_t i = 0; i < slices; ++i) b.tri(topPole + i, ring(1, i + 1), ring(1, i));
  for (uint32_t j = 1; j + 1 < stacks; ++j)
    for (uint32_t i = 0; i < slices; ++i) {
      uint32_t a = ring(j, i), bb = ring(j + 1, i), c = ring(j, i + 1), d = ring(j + 1, i + 1);
      b.tri(a, c, bb);
      b.tri(c, d, bb);
    }
  for (uint32_t i = 0; i < slices; ++i) b.tri(ring(stacks - 1, i), ring(stacks - 1, i + 1), bottomPole + i);
  return b.mesh;
}

MeshData makeCylinder(float radius, float height, uint32_t slices, uint32_t heightSegments, bool capped) {
  slices = std::max(slices, 3u);
  heightSegments = std::max(heightSegments, 1u);
  Builder b;
  b.mesh.name = "cylinder";
  for (uint32_t h = 0; h <= heightSegments; ++h)
    for (uint32_t i = 0; i <= slices; ++i) {
      float phi = float(i) / slices * 2.0f * kPi, y = height * h / heightSegments;
      glm::vec3 n(std::cos(phi), 0.0f, -std::sin(phi));
      b.add({n.x * radius, y, n.z * radius}, n, {float(i) / slices, 1.0f - float(h) / heightSegments},
            {-std::sin(phi), 0.0f, -std::cos(phi)});
    }
  gridTriangles(b, 0, slices, heightSegments);
  if (capped) {
    for (int top = 1; top >= 0; --top) {
      float y = top ? height : 0.0f;
      glm::vec3 n(0, top ? 1.0f : -1.0f, 0);
      uint32_t center = b.add({0, y, 0}, n, {0.5f, 0.5f}, {1, 0, 0});
      for (uint32_t i = 0; i <= slices; ++i) {
        float phi = float(i) / slices * 2.0f * kPi;
        glm::vec2 d(std::cos(phi), -std::sin(phi));
        b.add({d.x * radius, y, d.y * radius}, n, {0.5f + 0.5f * d.x, 0.5f + 0.5f * d.y}, {1, 0, 0});
      }
      for (uint32_t i = 0; i < slices; ++i) {
        if (top) b.tri(center, center + 1 + i, center + 2 + i);
        else
          b.tri(center, center + 2 + i, center + 1 + i);
      }
    }
  }
  return b.mesh;
}

MeshData makeArch(float majorRadius, float minorRadius, float arcRadians, uint32_t arcSegments, uint32_t tubeSegments) {
  arcSegments = std::max(arcSegments, 1u);
  tubeSegments = std::max(tubeSegments, 3u);
  Builder b;
  b.mesh.name = "arch";
  // Rows are tube angles, columns are arc angles: (a, b=next arc step, c=next tube step) winds outward.
  for (uint32_t t = 0; t <= tubeSegments; ++t)
    for (uint32_t a = 0; a <= arcSegments; ++a) {
      float alpha = arcRadians * a / arcSegments, beta = 2.0f * kPi * t / tubeSegments;
      glm::vec3 radial(std::cos(alpha), std::sin(alpha), 0.0f);
      glm::vec3 n = radial * std::cos(beta) + glm::vec3(0, 0, 1) * std::sin(beta);
      b.add(radial * majorRadius + n * minorRadius, n, {float(a) / arcSegments, float(t) / tubeSegments},
            {-std::sin(alpha), std::cos(alpha), 0.0f});
    }
  gridTriangles(b, 0, arcSegments, tubeSegments);
  return b.mesh;
}

}  // namespace sample_engine
