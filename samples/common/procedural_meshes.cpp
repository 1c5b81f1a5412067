#include "procedural_meshes.h"

#include <algorithm>
#include <cmath>

namespace rbsamples {

namespace {
constexpr float kPi = 3.14159265358979f;

void pushVertex(CpuMesh& m, float x, float y, float z, float nx, float ny, float nz) {
  m.positions.insert(m.positions.end(), {x, y, z});
  m.normals.insert(m.normals.end(), {nx, ny, nz});
}

void gridIndices(CpuMesh& m, uint32_t base, uint32_t cols, uint32_t rows) {
  for (uint32_t r = 0; r < rows; ++r) {
    for (uint32_t c = 0; c < cols; ++c) {
      uint32_t i0 = base + r * (cols + 1) + c, i1 = i0 + 1, i2 = i0 + cols + 1, i3 = i2 + 1;
      m.indices.insert(m.indices.end(), {i0, i2, i1, i1, i2, i3});
    }
  }
}
}  // namespace

CpuMesh makeGrid(float size, uint32_t cells) { return makeBumpyGrid(size, cells, 0.0f); }

CpuMesh makeBumpyGrid(float size, uint32_t cells, float amplitude) {
  CpuMesh m;
  cells = std::max(cells, 1u);
  for (uint32_t r = 0; r <= cells; ++r) {
    for (uint32_t c = 0; c <= cells; ++c) {
      float x = -size / 2 + size * float(c) / float(cells);
      float z = -size / 2 + size * float(r) / float(cells);
      float k = 6.0f * kPi / size;
      float y = amplitude * std::sin(k * x) * std::cos(k * z);
      float dx = amplitude * k * std::cos(k * x) * std::cos(k * z);
      float dz = -amplitude * k * std::sin(k * x) * std::sin(k * z);
      float len = std::sqrt(dx * dx + 1 + dz * dz);
      pushVertex(m, x, y, z, -dx / len, 1 / len, -dz / len);
    }
  }
  gridIndices(m, 0, cells, cells);
  return m;
}

CpuMesh makeSphere(float radius, uint32_t slices, uint32_t stacks) {
  CpuMesh m;
  slices = std::max(slices, 3u);
  stacks = std::max(stacks, 2u);
  for (uint32_t s = 0; s <= stacks; ++s) {
    float phi = kPi * float(s) / float(stacks);
    for (uint32_t i = 0; i <= slices; ++i) {
      float theta = 2 * kPi * float(i) / float(slices);
      float nx = std::sin(phi) * std::cos(theta), ny = std::cos(phi), nz = -std::sin(phi) * std::sin(theta);
      pushVertex(m, radius * nx, radius * ny, radius * nz, nx, ny, nz);
    }
  }
  for (uint32_t s = 0; s < stacks; ++s) {
    for (uint32_t i = 0; i < slices; ++i) {
      uint32_t a = s * (slices + 1) + i, b = a + slices + 1;
      // The pole rows would produce degenerate triangles: keep one triangle per quad there.
      if (s != 0) m.indices.insert(m.indices.end(), {a, b, a + 1});
      if (s != stacks - 1) m.indices.insert(m.indices.end(), {a + 1, b, b + 1});
    }
  }
  return m;
}

CpuMesh makeBox(const float mn[3], const float mx[3], uint32_t cells) {
  CpuMesh m;
  cells = std::max(cells, 1u);
  // Each face: origin corner, two edge vectors (u, v) with u x v pointing outwards.
  struct Face {
    float o[3], u[3], v[3], n[3];
  };
  float sx = mx[0] - mn[0], sy = mx[1] - mn[1], sz = mx[2] - mn[2];
  const Face faces[6] = {
      {{mx[0], mn[1], mx[2]}, {0, 0, -sz}, {0, sy, 0}, {1, 0, 0}},
      {{mn[0], mn[1], mn[2]}, {0, 0, sz}, {0, sy, 0}, {-1, 0, 0}},
      {{mn[0], mx[1], mx[2]}, {sx, 0, 0}, {0, 0, -sz}, {0, 1, 0}},
      {{mn[0], mn[1], mn[2]}, {sx, 0, 0}, {0, 0, sz}, {0, -1, 0}},
      {{mn[0], mn[1], mx[2]}, {sx, 0, 0}, {0, sy, 0}, {0, 0, 1}},
      {{mx[0], mn[1], mn[2]}, {-sx, 0, 0}, {0, sy, 0}, {0, 0, -1}},
  };
  for (const Face& f : faces) {
    uint32_t base = m.vertexCount();
    for (uint32_t r = 0; r <= cells; ++r) {
      for (uint32_t c = 0; c <= cells; ++c) {
        float a = float(c) / float(cells), b = float(r) / float(cells);
        pushVertex(m, f.o[0] + a * f.u[0] + b * f.v[0], f.o[1] + a * f.u[1] + b * f.v[1],
                   f.o[2] + a * f.u[2] + b * f.v[2], f.n[0], f.n[1], f.n[2]);
      }
    }
    // gridIndices winds (i0, i2, i1): with rows along v and columns along u that faces u x v.
    for (uint32_t r = 0; r < cells; ++r) {
      for (uint32_t c = 0; c < cells; ++c) {
        uint32_t i0 = base + r * (cells + 1) + c, i1 = i0 + 1, i2 = i0 + cells + 1, i3 = i2 + 1;
        m.indices.insert(m.indices.end(), {i0, i1, i2, i1, i3, i2});
      }
    }
  }
  return m;
}

CpuMesh makeSphereWithAbout(uint64_t triangles, float radius) {
  // 2 * slices * (stacks - 1) triangles with slices = 2 * stacks.
  uint32_t stacks = std::max<uint32_t>(2, static_cast<uint32_t>(std::sqrt(double(triangles) / 4.0)));
  return makeSphere(radius, 2 * stacks, stacks);
}

void appendTranslated(CpuMesh& into, const CpuMesh& mesh, float dx, float dy, float dz) {
  uint32_t base = into.vertexCount();
  for (size_t i = 0; i < mesh.positions.size(); i += 3) {
    into.positions.insert(into.positions.end(),
                          {mesh.positions[i] + dx, mesh.positions[i + 1] + dy, mesh.positions[i + 2] + dz});
  }
  into.normals.insert(into.normals.end(), mesh.normals.begin(), mesh.normals.end());
  for (uint32_t i : mesh.indices) into.indices.push_back(base + i);
}

}  // namespace rbsamples
