// Procedural triangle meshes with known triangle counts, for the benchmark, the tests and the default scenes.
// Pure CPU data; knows nothing of Vulkan or Raybridge.
#pragma once

#include <cstdint>
#include <vector>

namespace rbsamples {

struct CpuMesh {
  std::vector<float> positions;   // xyz per vertex
  std::vector<float> normals;     // xyz per vertex (smooth where the surface is smooth)
  std::vector<uint32_t> indices;  // three per triangle, counter-clockwise seen from outside
  uint32_t vertexCount() const { return static_cast<uint32_t>(positions.size() / 3); }
  uint32_t triangleCount() const { return static_cast<uint32_t>(indices.size() / 3); }
};

// A square in the XZ plane centred at the origin, facing +Y: 2 * cells * cells triangles.
CpuMesh makeGrid(float size, uint32_t cells);
// A height field over a grid (deterministic sine bumps of the given amplitude): 2 * cells * cells triangles.
CpuMesh makeBumpyGrid(float size, uint32_t cells, float amplitude);
// A UV sphere: 2 * slices * (stacks - 1) triangles.
CpuMesh makeSphere(float radius, uint32_t slices, uint32_t stacks);
// An axis-aligned box from min to max, each face split into cells x cells quads: 12 * cells * cells triangles.
CpuMesh makeBox(const float min[3], const float max[3], uint32_t cells = 1);
// A sphere of about `triangles` triangles (rounded to the UV-sphere grid), for build-rate sweeps.
CpuMesh makeSphereWithAbout(uint64_t triangles, float radius);

// Appends `mesh` translated by (dx, dy, dz).
void appendTranslated(CpuMesh& into, const CpuMesh& mesh, float dx, float dy, float dz);

}  // namespace rbsamples
