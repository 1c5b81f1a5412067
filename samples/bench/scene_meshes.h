// Procedural scene pieces for the scenarios: tessellated grounds and spheres of a given size, instance
// transforms, bounds and a camera that frames them.
#pragma once

#include <raybridge/raybridge.h>

#include <array>
#include <cstdint>
#include <vector>

#include "procedural_meshes.h"

namespace rbbench {

using Transform = std::array<float, 12>;  // row-major 3x4, the layout of rb::Instance::transform

Transform translation(float x, float y, float z);
Transform scaledTranslation(float scale, float x, float y, float z);
void setTransform(rb::Instance& instance, const Transform& t);

// A bumpy height field of about `triangles` triangles over size x size (a realistic, finely tessellated ground).
rbsamples::CpuMesh groundWithAbout(uint64_t triangles, float size);

struct Bounds {
  float min[3] = {1e30f, 1e30f, 1e30f};
  float max[3] = {-1e30f, -1e30f, -1e30f};
  void add(const rbsamples::CpuMesh& mesh, const Transform& t);
  void add(const Bounds& b);
  bool empty() const { return min[0] > max[0]; }
};
Bounds boundsOf(const rbsamples::CpuMesh& mesh);

// Looks at the centre of `b` from direction `from` (default: above and to the side), far enough that the whole
// box is in view.
rb::PrimaryRayCamera cameraFraming(const Bounds& b, std::array<float, 3> from = {0.45f, 0.6f, 0.66f});
// Looks down at a ground of size x size centred on the origin (groundWithAbout) so that every primary ray at a
// 16:9 or squarer aspect hits it.
rb::PrimaryRayCamera cameraOverGround(float size);
// Grid positions for `count` copies of an object of extent `spacing`, centred on the origin in XZ.
std::vector<Transform> gridPlacement(uint32_t count, float spacing);

}  // namespace rbbench
