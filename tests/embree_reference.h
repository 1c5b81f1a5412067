// An independent reference tracer (Embree 3) over the same meshes and instance transforms as a Raybridge TLAS.
#pragma once

#include <cstdint>
#include <vector>

#include "procedural_meshes.h"

namespace rbtest {

struct ReferenceHit {
  bool hit = false;
  float t = 0.0f;
  uint32_t primitiveId = 0xFFFFFFFFu;
  uint32_t instanceId = 0xFFFFFFFFu;     // the id passed to addInstance
  float geometricNormal[3] = {0, 0, 0};  // world space, unnormalised
};

class EmbreeScene {
 public:
  EmbreeScene();
  ~EmbreeScene();
  EmbreeScene(const EmbreeScene&) = delete;
  EmbreeScene& operator=(const EmbreeScene&) = delete;

  // Adds `mesh` transformed by the row-major 3x4 matrix (flattened into world space in double precision).
  void addInstance(const rbsamples::CpuMesh& mesh, const float transform[12], uint32_t instanceId);
  void commit();
  ReferenceHit intersect(const float origin[3], const float direction[3], float tMin, float tMax) const;

 private:
  struct State;
  State* state_;
};

}  // namespace rbtest
