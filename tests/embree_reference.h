// An independent reference tracer (Embree 3) over the same meshes and instance transforms as a Raybridge TLAS.
#pragma once

#include <cstdint>
#include <functional>
#include <vector>

#include "procedural_meshes.h"

namespace rbtest {

struct ReferenceHit {
  bool hit = false;
  float t = 0.0f;
  uint32_t primitiveId = 0xFFFFFFFFu;
  uint32_t instanceId = 0xFFFFFFFFu;     // the id passed to addInstance
  float geometricNormal[3] = {0, 0, 0};  // world space, unnormalised
  float barycentrics[2] = {0, 0};        // of vertices 1 and 2 (vertex 0 weighs 1 - both), as Vulkan's
};

// Whether a hit stops the ray (true) or the ray passes through it (an alpha cut-out).
using HitFilter = std::function<bool(const ReferenceHit&)>;

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
  // The nearest hit `stops` accepts: intersects, and continues the ray past every hit it rejects.
  ReferenceHit intersect(const float origin[3], const float direction[3], float tMin, float tMax,
                         const HitFilter& stops) const;

 private:
  struct State;
  State* state_;
};

}  // namespace rbtest
